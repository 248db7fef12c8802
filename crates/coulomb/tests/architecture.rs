//! The library's and the command line's modules import each other without circles
//! (`scripts/import_circles.py`, docs/solver-core.md): a module may use those below it, never
//! one that uses it back. (coulomb-granular still has four: issue 52, docs/architecture.md.)

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
fn the_command_line_has_no_import_circle() {
    assert_no_import_circle("crates/coulomb-cli/src");
}
