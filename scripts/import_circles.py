#!/usr/bin/env python3
"""Import circles between the modules of a Rust crate (issue #42 item 6).

    scripts/import_circles.py [SRC_DIR]    (default: crates/coulomb/src)

Each .rs file is a module (foo.rs and foo/mod.rs: `foo`; foo/bar.rs: `foo::bar`). A module
depends on another when its text (tests included, comments excluded) names `crate::a::b…`
or `super::…` leading to it: the longest prefix of the path that is a module (in the file's
inline test module, `super` is the file's own module), through `pub use` re-exports: of a
module under another name, of a module's items by glob, and of single items (`pub use
a::b::Item;` in module m: `crate::m::Item` leads to `a::b`, the module that defines it, not
to m). Prints every
strongly connected component of two or more modules (an import circle), largest first, then
the edges inside each, and exits 1 when there is one (0 otherwise).
"""

import os
import re
import sys


def modules(src):
    mods = {}
    for root, _, files in os.walk(src):
        for f in files:
            if not f.endswith(".rs"):
                continue
            path = os.path.join(root, f)
            rel = os.path.relpath(path, src)[:-3].split(os.sep)
            if rel[-1] == "mod" or rel == ["lib"]:
                rel = rel[:-1]
            mods["::".join(rel)] = path
    return mods


def strip_comments(text):
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def reexports(mods):
    """Modules re-exported under another path by `pub use` in a module file: `pub use a::b;`,
    `pub use a::{b, c as d};` (aliases: the new path -> the module) and `pub use a::*;`
    (globs: the re-exporting module -> the modules whose items it re-exports)."""
    aliases, globs, items_of = {}, {}, []
    stmt = re.compile(r"\bpub(?:\([a-z]+\))?\s+use\s+(?:self::)?([^;]*);", re.S)
    for m, path in mods.items():
        text = strip_comments(open(path, encoding="utf-8").read())
        prefix = m.split("::") if m else []
        for rest in stmt.findall(text):
            head, _, group = rest.partition("{")
            head = [p for p in head.strip().strip(":").split("::") if p]
            items = [g.strip() for g in group.rstrip("}").split(",")] if group else [""]
            for item in items:
                if not item and not head:
                    continue
                name, _, alias = item.partition(" as ")
                full = prefix + head + [p for p in name.strip().split("::") if p]
                if full and full[-1] == "*":
                    target = "::".join(full[:-1])
                    if target in mods:
                        globs.setdefault(m, []).append(target)
                    continue
                target = "::".join(full)
                new = prefix + [(alias or full[-1]).strip()]
                if target in mods:
                    if "::".join(new) != target:
                        aliases["::".join(new)] = target
                else:
                    items_of.append(("::".join(new), full[:-1]))
    # items re-exported (`pub use a::b::Item;`): a path through the new name leads to the
    # module that defines the item (resolved once the module aliases are known)
    for new, parent in items_of:
        owner = resolve(parent, mods, aliases, globs) if parent else None
        if owner and new not in aliases and new not in mods:
            aliases[new] = owner
    return aliases, globs


def resolve(path, mods, aliases=None, globs=None):
    """The longest prefix of `path` (a list of names) that is a module, through the
    re-exports (`reexports`)."""
    aliases, globs = aliases or {}, globs or {}
    for k in range(len(path), 0, -1):
        name = "::".join(path[:k])
        if name in aliases:
            path = aliases[name].split("::") + path[k:]
            break
    for k in range(len(path), 0, -1):
        name = "::".join(path[:k])
        if name in mods:
            if k < len(path) and globs.get(name):
                return globs[name][0]
            return name
    return None


def paths_of(text, base, use_group, inline):
    """The `crate::…` and `super::…` paths that `text` names, `base` giving each root's path."""
    paths = []
    for root, rest in use_group.findall(text):
        # use crate::a::{b, c::d}: the prefix and each item of the group
        head, _, group = rest.partition("{")
        head = [p for p in head.strip().strip(":").split("::") if p]
        items = [g.strip() for g in group.rstrip("}").split(",")] if group else [""]
        for item in items:
            tail = [p for p in re.split(r"::|\s+as\s+", item)[:2] if p and p != "self"]
            paths.append(base[root] + head + tail)
    for root, rest in inline.findall(text):
        paths.append(base[root] + rest.strip(":").split("::"))
    return paths


def edges(mods):
    out = {m: set() for m in mods}
    aliases, globs = reexports(mods)
    use_group = re.compile(r"\buse\s+(crate|super)::([^;]*);", re.S)
    inline = re.compile(r"\b(crate|super)((?:::[A-Za-z_][A-Za-z0-9_]*)+)")
    # `#[cfg(test)]`, or the unit tests compiled into the library (scripts/unit_tests.py):
    # `#[cfg(feature = "unit-tests")]`, alone or in an `all(…)`
    test_mod = re.compile(
        r'#\[cfg\((?:test|feature = "unit-tests"|all\([^)]*feature = "unit-tests"[^)]*\))\)\]'
        r"\s*(?:pub(?:\([a-z]+\))?\s+)?mod\s+\w+\s*\{"
    )
    for m, path in mods.items():
        text = strip_comments(open(path, encoding="utf-8").read())
        parent = m.split("::")[:-1] if m else []
        # inside the file's inline test module (`#[cfg(test)] mod tests { … }` or its
        # `unit-tests` form, at its end),
        # `super` is the file's own module
        inner = test_mod.search(text)
        parts = [(text, parent)]
        if inner is not None:
            parts = [(text[: inner.start()], parent), (text[inner.start():], m.split("::") if m else [])]
        paths = []
        for part, sup in parts:
            paths += paths_of(part, {"crate": [], "super": sup}, use_group, inline)
        for p in paths:
            target = resolve(p, mods, aliases, globs)
            if target is not None and target != m and not m.startswith(target + "::") and target != "":
                out[m].add(target)
    return out


def sccs(graph):
    index, low, stack, on, comps, counter = {}, {}, [], set(), [], [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            comps.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return comps


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else "crates/coulomb/src"
    mods = modules(src)
    graph = edges(mods)
    circles = sorted((c for c in sccs(graph) if len(c) > 1), key=len, reverse=True)
    print(f"{len(mods)} modules, {sum(len(e) for e in graph.values())} dependencies, "
          f"{len(circles)} import circle(s)")
    for c in circles:
        print(f"\ncircle of {len(c)} modules: {', '.join(c)}")
        inside = set(c)
        for m in c:
            deps = sorted(graph[m] & inside)
            print(f"  {m} -> {', '.join(deps)}")
    return 1 if circles else 0


if __name__ == "__main__":
    sys.exit(main())
