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

/// The script sees a circle hidden behind the crate root's re-export of an item: `b` names
/// `crate::Thing`, which `lib.rs` re-exports from `a`, and `a` uses `b`.
#[test]
fn a_circle_through_a_re_exported_item_is_found() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = std::env::temp_dir().join(format!("coulomb-circle-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    let files = [
        ("lib.rs", "pub mod a;\npub mod b;\npub use a::Thing;\n"),
        (
            "a.rs",
            "use crate::b::helper;\npub struct Thing;\npub fn f() { helper() }\n",
        ),
        ("b.rs", "pub fn helper() {}\npub fn g(_: crate::Thing) {}\n"),
    ];
    for (name, text) in files {
        std::fs::write(dir.join(name), text).expect("a scratch file");
    }
    let out = Command::new("python3")
        .arg(root.join("scripts/import_circles.py"))
        .arg(&dir)
        .output()
        .expect("python3 runs");
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    std::fs::remove_dir_all(&dir).ok();
    assert!(
        !out.status.success() && text.contains(" 1 import circle(s)") && text.contains("a, b"),
        "{text}"
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
