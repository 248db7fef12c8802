#!/usr/bin/env python3
"""The unit tests of a crate compiled into its library (docs/testing.md, "Unit tests in the
library"): writes, from the crate's sources, the two files that run them.

A crate whose `[lib]` has `test = false` keeps its unit tests in modules gated by its feature
`unit-tests` (`#[cfg(feature = "unit-tests")] pub mod tests`), each test a `pub fn name()`
taking nothing (`#[ignore = "…"]` on it as on a `#[test]`). Its integration test binary, built
with the feature (the crate is its own dev-dependency with it), calls them. So the test build
compiles the crate once, where a `#[cfg(test)]` module compiles the whole crate a second time
as a test harness. This script writes

  src/unit_tests.rs   the test modules re-exported under the crate's `unit_tests` module
                      (the paths mirrored: `unit_tests::step::rigid::tests`);
  tests/unit.rs       one `#[test]` per test, at the same path under `unit::`, calling it.

    python3 scripts/unit_tests.py CRATE_DIR           write both
    python3 scripts/unit_tests.py CRATE_DIR --check   exit 1 when either is stale

(the integration test `architecture::every_unit_test_is_run` runs the check). Both files are
written as rustfmt formats them. Both commands fail on a `#[test]` or a `cfg(test)` in the
crate's sources, which such a crate never compiles.
"""
import os
import re
import subprocess
import sys

FEATURE = 'feature = "unit-tests"'


def strip_code(text):
    """`text` with the contents of comments, strings and char literals blanked (same length,
    newlines kept), so that braces and keywords are found only in code."""
    out = list(text)
    i, n = 0, len(text)

    def blank(a, b):
        for k in range(a, b):
            if out[k] != "\n":
                out[k] = " "

    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            blank(i, j)
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            blank(i, j)
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:]) and not (i and (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'r(#*)"', text[i:])
            end = '"' + m.group(1)
            j = text.find(end, i + len(m.group(0)))
            j = n if j < 0 else j + len(end)
            blank(i + 1, j)
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            blank(i + 1, j)
            i = j + 1
        elif c == "'":
            # a char literal ('x', '\n', '\u{..}') or a lifetime ('a)
            if i + 1 < n and text[i + 1] == "\\":
                j = text.find("'", i + 2)
                blank(i + 1, j)
                i = j + 1
            elif i + 2 < n and text[i + 2] == "'":
                blank(i + 1, i + 2)
                i += 3
            else:
                i += 1
        else:
            i += 1
    return "".join(out)


def matching_brace(code, open_at):
    depth = 0
    for k in range(open_at, len(code)):
        if code[k] == "{":
            depth += 1
        elif code[k] == "}":
            depth -= 1
            if depth == 0:
                return k
    raise SystemExit(f"unbalanced braces from offset {open_at}")


def module_path(src, path):
    rel = os.path.relpath(path, src)[:-3].split(os.sep)
    if rel[-1] in ("lib", "mod"):
        rel = rel[:-1]
    return rel


def child_file(src, path, name):
    """The file of `mod name;` declared in `path`."""
    base = os.path.dirname(path)
    stem = os.path.basename(path)[:-3]
    d = base if stem in ("lib", "mod") else os.path.join(base, stem)
    for f in (os.path.join(d, name + ".rs"), os.path.join(d, name, "mod.rs")):
        if os.path.exists(f):
            return f
    raise SystemExit(f"{path}: no file for `mod {name};`")


ATTR = re.compile(r"^[ \t]*#\[([^\]]*)\][ \t]*$", re.M)
MOD = re.compile(r"^[ \t]*(pub(?:\([a-z]+\))? )?mod (\w+)[ \t]*(\{|;)", re.M)
FN = re.compile(r"^[ \t]*pub fn (\w+)\(\)[ \t]*(\{|->)", re.M)


def attrs_before(text, at):
    """The attribute lines just above offset `at` (doc comments skipped), innermost last."""
    lines = text[:at].split("\n")[:-1]
    got = []
    while lines:
        s = lines[-1].strip()
        if s.startswith("#["):
            got.append(s)
        elif not s.startswith("///"):
            break
        lines.pop()
    return got[::-1]


def cfg_rest(attrs):
    """For a unit-test module's attributes: (is a unit-test module, the other cfg condition)."""
    for a in attrs:
        m = re.fullmatch(r"#\[cfg\((.*)\)\]", a)
        if not m:
            continue
        cond = m.group(1)
        if cond == FEATURE:
            return True, None
        m2 = re.fullmatch(r"all\((.*)\)", cond)
        if m2:
            parts = [p.strip() for p in m2.group(1).split(",")]
            if FEATURE in parts:
                rest = [p for p in parts if p != FEATURE]
                return True, rest[0] if len(rest) == 1 else "all(" + ", ".join(rest) + ")"
    return False, None


def other_cfgs(attrs):
    return [a for a in attrs if a.startswith("#[cfg(") and FEATURE not in a]


def tests_in(path, text, code, start, end):
    """The tests (name, #[ignore] attribute or None) directly in the module body [start, end)."""
    level = []  # brace depth, relative to the body, of each of its characters
    d = 0
    for ch in code[start:end]:
        level.append(d)
        d += (ch == "{") - (ch == "}")
    found = []
    for m in FN.finditer(code, start, end):
        if level[m.start() - start] != 0:
            continue
        if m.group(2) == "->":
            line = code.count("\n", 0, m.start()) + 1
            raise SystemExit(
                f"{path}:{line}: the test `{m.group(1)}` returns a value; a unit test is a"
                " `pub fn name()` returning nothing (panic on failure)"
            )
        attrs = attrs_before(text, m.start())
        ignore = next((a for a in attrs if a.startswith("#[ignore")), None)
        found.append((m.group(1), ignore))
    return found


def scan(src):
    """Every unit-test module: (module path, test module name, extra cfg, tests)."""
    out = []

    def visit(path, modpath, gates):
        text = open(path, encoding="utf-8").read()
        code = strip_code(text)
        inline_ranges = []
        for m in MOD.finditer(code):
            if any(a < m.start() < b for a, b in inline_ranges):
                continue
            name = m.group(2)
            if not modpath and name == "unit_tests":
                continue  # this script's own output
            attrs = attrs_before(text, m.start())
            is_unit, rest = cfg_rest(attrs)
            g = gates + other_cfgs(attrs) + ([f"#[cfg({rest})]"] if rest else [])
            if m.group(3) == "{":
                open_at = code.index("{", m.start())
                close = matching_brace(code, open_at)
                inline_ranges.append((m.start(), close))
                if is_unit:
                    tests = tests_in(path, text, code, open_at + 1, close)
                    if tests:
                        out.append((modpath, name, g, tests, path))
            else:
                f = child_file(src, path, name)
                if is_unit:
                    t2 = open(f, encoding="utf-8").read()
                    tests = tests_in(f, t2, strip_code(t2), 0, len(t2))
                    if tests:
                        out.append((modpath, name, g, tests, f))
                else:
                    visit(f, modpath + [name], g)

    visit(os.path.join(src, "lib.rs"), [], [])
    return out


def tree(mods):
    root = {}
    for modpath, name, gates, tests, _ in mods:
        node = root
        for p in modpath:
            node = node.setdefault(("mod", p), {})
        node[("leaf", name)] = (modpath, gates, tests)
    return root


def gates_of(node):
    """The cfg attributes every leaf below `node` shares (a folder gated by a feature)."""
    leaves = []

    def walk(n):
        for k, v in n.items():
            if k[0] == "leaf":
                leaves.append(v[1])
            else:
                walk(v)

    walk(node)
    common = set(leaves[0]) if leaves else set()
    for g in leaves[1:]:
        common &= set(g)
    return [g for g in leaves[0] if g in common] if leaves else []


def render(root, header, module_kw, leaf):
    """The tree of modules as Rust: `module_kw` opens a folder's module (`pub mod`, `mod`),
    `leaf(path, name, tests, indent)` gives the lines of a test module; a cfg every test below a
    folder shares is written once, on the folder."""
    lines = list(header)

    def emit(node, depth, outer):
        ind = "    " * depth
        for k in sorted(node, key=lambda k: (k[0] != "leaf", k[1])):
            v = node[k]
            gates = v[1] if k[0] == "leaf" else gates_of(v)
            lines.extend(ind + g for g in gates if g not in outer)
            if k[0] == "leaf":
                lines.extend(leaf(v[0], k[1], v[2], ind))
            else:
                lines.append(f"{ind}{module_kw} {k[1]} {{")
                emit(v, depth + 1, outer + gates)
                lines.append(ind + "}")

    emit(root, 0, [])
    return "\n".join(lines) + "\n"


def render_reexports(root):
    header = [
        "//! The crate's unit tests, re-exported for its integration test binary",
        "//! (`tests/unit.rs`). Written by `scripts/unit_tests.py`; do not edit.",
        "",
    ]

    def leaf(modpath, name, _tests, ind):
        return [f"{ind}pub use crate::{'::'.join(modpath + [name])};"]

    return render(root, header, "pub mod", leaf)


def render_wrappers(root, crate):
    header = [
        f"//! The unit tests of `{crate}` (modules `#[cfg(feature = \"unit-tests\")] pub mod tests`",
        "//! of its library), each run by a `#[test]` at its module's path: compiled once, with the",
        "//! library, instead of in a second build of the whole crate as a test harness",
        "//! (docs/testing.md). Written by `scripts/unit_tests.py`; do not edit.",
        "",
    ]

    def leaf(modpath, name, tests, ind):
        out = [f"{ind}mod {name} {{", f"{ind}    use {crate}::unit_tests::{'::'.join(modpath + [name])} as t;"]
        for test, ignore in tests:
            out.append(f"{ind}    #[test]")
            if ignore:
                out.append(f"{ind}    {ignore}")
            out += [f"{ind}    fn {test}() {{", f"{ind}        t::{test}()", f"{ind}    }}"]
        return out + [ind + "}"]

    return render(root, header, "mod", leaf)


def formatted(text):
    """`text` as `cargo fmt` leaves it (rustfmt, the workspace's edition and default settings),
    so that the files written are the ones the format check accepts."""
    out = subprocess.run(
        ["rustfmt", "--edition", "2021", "--emit", "stdout"],
        input=text, capture_output=True, text=True,
    )
    if out.returncode != 0:
        raise SystemExit("rustfmt failed:\n" + out.stderr)
    return out.stdout


def never_run(src):
    """`file:line` of each `#[test]` or `cfg(test)` in the crate's code: with `[lib] test =
    false` neither is ever compiled, so a test written that way would silently never run."""
    found = []
    pat = re.compile(r"#\[test\]|\bcfg(?:_attr)?!?\((?:[^()]*\()?[^()]*\btest\b")
    for d, _, fs in sorted(os.walk(src)):
        for f in sorted(fs):
            if not f.endswith(".rs"):
                continue
            path = os.path.join(d, f)
            code = strip_code(open(path, encoding="utf-8").read())
            for m in pat.finditer(code):
                line = code.count("\n", 0, m.start()) + 1
                found.append(f"{path}:{line}: `{m.group(0)}`")
    return found


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    check = "--check" in sys.argv
    if len(args) != 1:
        raise SystemExit(__doc__)
    crate_dir = args[0]
    src = os.path.join(crate_dir, "src")
    crate = re.search(r'^name = "([^"]+)"', open(os.path.join(crate_dir, "Cargo.toml")).read(), re.M)
    crate = crate.group(1).replace("-", "_")
    wrong = never_run(src)
    if wrong:
        print(
            "never compiled in a crate whose tests are in its library (a test is a `pub fn` in a"
            " `#[cfg(feature = \"unit-tests\")] pub mod`, docs/testing.md):\n  " + "\n  ".join(wrong)
        )
        sys.exit(1)
    mods = scan(src)
    root = tree(mods)
    files = {
        os.path.join(src, "unit_tests.rs"): formatted(render_reexports(root)),
        os.path.join(crate_dir, "tests", "unit.rs"): formatted(render_wrappers(root, crate)),
    }
    stale = []
    for path, text in files.items():
        old = open(path, encoding="utf-8").read() if os.path.exists(path) else None
        if old != text:
            stale.append(path)
            if not check:
                # written whole or not at all: a temporary file beside it, then renamed
                tmp = path + ".tmp"
                with open(tmp, "w", encoding="utf-8") as f:
                    f.write(text)
                os.replace(tmp, path)
    n = sum(len(t) for _, _, _, t, _ in mods)
    if check and stale:
        print(f"stale (run `python3 scripts/unit_tests.py {crate_dir}`): {', '.join(stale)}")
        sys.exit(1)
    print(f"{crate}: {n} unit tests in {len(mods)} modules" + ("" if check else f"; wrote {len(stale)} file(s)"))


if __name__ == "__main__":
    main()
