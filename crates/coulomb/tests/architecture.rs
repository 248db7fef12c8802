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

fn unit_tests_script(crate_dir: &Path, check: bool) -> std::process::Output {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut cmd = Command::new("python3");
    cmd.arg(root.join("scripts/unit_tests.py")).arg(crate_dir);
    if check {
        cmd.arg("--check");
    }
    cmd.output()
        .expect("python3 runs (the test command needs it for the Python tests too)")
}

/// A crate whose unit tests are compiled into its library (`[lib] test = false`, feature
/// `unit-tests`, docs/testing.md) runs each of them from `tests/unit.rs`: that file and the
/// crate's re-exports `src/unit_tests.rs` are what `scripts/unit_tests.py` writes from the
/// sources, so a test added to a module and not to them fails here instead of never running.
#[test]
fn every_unit_test_is_run() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    for krate in ["coulomb", "coulomb-granular"] {
        let out = unit_tests_script(&root.join("crates").join(krate), true);
        assert!(
            out.status.success(),
            "{krate}: {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// The script finds a test added to a unit-test module (also one gated by another cfg, and
/// an ignored one), calls the check stale until it is run, and writes a `#[test]` for each;
/// it refuses a `#[test]` in the sources, which such a crate would never compile, and a test
/// that returns a value.
#[test]
fn a_new_unit_test_makes_the_check_fail_until_it_is_written() {
    let dir = std::env::temp_dir().join(format!("coulomb-unit-tests-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("src/a")).expect("a scratch crate");
    std::fs::create_dir_all(dir.join("tests")).expect("a scratch crate");
    let write = |p: &str, t: &str| std::fs::write(dir.join(p), t).expect("a scratch file");
    write("Cargo.toml", "[package]\nname = \"scratch-crate\"\n");
    write(
        "src/lib.rs",
        "pub mod a;\n#[cfg(feature = \"unit-tests\")]\npub mod unit_tests;\n",
    );
    write(
        "src/a/mod.rs",
        "mod b;\n#[cfg(feature = \"unit-tests\")]\npub mod tests {\n    \
         pub fn one() {\n        let s = \"}\";\n        assert_eq!(s, \"}\");\n    }\n    \
         fn helper() {}\n}\n",
    );
    write(
        "src/a/b.rs",
        "#[cfg(all(feature = \"unit-tests\", unix))]\npub mod tests {\n    \
         #[ignore = \"long\"]\n    pub fn two() {}\n}\n",
    );
    assert!(
        !unit_tests_script(&dir, true).status.success(),
        "stale before writing"
    );
    assert!(unit_tests_script(&dir, false).status.success());
    assert!(
        unit_tests_script(&dir, true).status.success(),
        "current after writing"
    );
    let wrappers = std::fs::read_to_string(dir.join("tests/unit.rs")).expect("written");
    let exports = std::fs::read_to_string(dir.join("src/unit_tests.rs")).expect("written");
    // a `#[test]` by habit would never be compiled in such a crate: refused, with its line
    write(
        "src/a/b.rs",
        "#[cfg(all(feature = \"unit-tests\", unix))]\npub mod tests {\n    \
         #[test]\n    fn forgotten() {}\n}\n",
    );
    let refused = unit_tests_script(&dir, false);
    // nor is a test returning a value taken silently as none
    write(
        "src/a/b.rs",
        "#[cfg(feature = \"unit-tests\")]\npub mod tests {\n    \
         pub fn three() -> Result<(), String> {\n        Ok(())\n    }\n}\n",
    );
    let returning = unit_tests_script(&dir, false);
    let _ = std::fs::remove_dir_all(&dir);
    let said = String::from_utf8_lossy(&refused.stdout);
    assert!(!refused.status.success(), "{said}");
    assert!(said.contains("b.rs:3: `#[test]`"), "{said}");
    let said = String::from_utf8_lossy(&returning.stderr);
    assert!(!returning.status.success(), "{said}");
    assert!(
        said.contains("b.rs:3: the test `three` returns a value"),
        "{said}"
    );
    assert!(
        wrappers.contains("fn one() {\n") && wrappers.contains("t::one()"),
        "{wrappers}"
    );
    assert!(wrappers.contains("#[ignore = \"long\"]\n") && wrappers.contains("t::two()"));
    assert!(!wrappers.contains("helper"), "{wrappers}");
    assert!(wrappers.contains("#[cfg(unix)]"), "{wrappers}");
    assert!(exports.contains("pub use crate::a::b::tests;"), "{exports}");
    assert!(exports.contains("pub use crate::a::tests;"), "{exports}");
}
