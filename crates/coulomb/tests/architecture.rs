//! The library's, the simulator's and the command line's modules import each other without
//! circles (`scripts/import_circles.py`, docs/solver-core.md, docs/architecture.md): a module
//! may use those below it, never one that uses it back.

use std::path::Path;
use std::process::Command;

fn assert_no_import_circle(src: &str) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let out = Command::new("python3")
        .arg(root.join("scripts/import_circles.py"))
        .arg(root.join(src))
        .output()
        .expect("python3 runs (the test command needs it for the Python tests too)");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains(" 0 import circle(s)"),
        "import circles in {src}:\n{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn the_library_has_no_import_circle() {
    assert_no_import_circle("crates/coulomb/src");
}

#[test]
fn the_simulator_has_no_import_circle() {
    assert_no_import_circle("crates/coulomb-granular/src");
}

#[test]
fn the_command_line_has_no_import_circle() {
    assert_no_import_circle("crates/coulomb-cli/src");
}

/// With `autotests = false` a file of `tests/` that `tests/main.rs` does not declare as a
/// module is silently not compiled: every crate's files are declared there.
#[test]
fn every_test_file_is_compiled() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut missing = Vec::new();
    for krate in ["coulomb", "coulomb-cli", "coulomb-granular"] {
        let dir = root.join("crates").join(krate).join("tests");
        let declared = std::fs::read_to_string(dir.join("main.rs")).expect("tests/main.rs");
        for entry in std::fs::read_dir(&dir).expect("tests/ is readable") {
            let path = entry.expect("a directory entry").path();
            let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else {
                continue;
            };
            if path.extension().is_some_and(|e| e == "rs")
                && stem != "main"
                && !declared.contains(&format!("\nmod {stem};"))
            {
                missing.push(format!("{krate}/tests/{stem}.rs"));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "not declared as modules in their tests/main.rs: {missing:?}"
    );
}
