//! The library's modules import each other without circles (`scripts/import_circles.py`,
//! docs/solver-core.md): a module may use those below it, never one that uses it back.

use std::path::Path;
use std::process::Command;

#[test]
fn the_library_has_no_import_circle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let out = Command::new("python3")
        .arg(root.join("scripts/import_circles.py"))
        .arg(root.join("crates/coulomb/src"))
        .output()
        .expect("python3 runs (the test command needs it for the Python tests too)");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains(" 0 import circle(s)"),
        "import circles in crates/coulomb/src:\n{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
