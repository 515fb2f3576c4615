#!/usr/bin/env python3
"""Fails when a crate's modules import each other in a circle, or reach up into the commands.

- **No cycle among siblings, at any depth.** Within each parent module, its children must
  import one another one way only: an import by any module inside child `a` of anything inside
  its sibling `b` is an edge a -> b, and the edges among the children of each parent must form
  no cycle. Imports are the `crate::` and `super::` paths of the code (`use` lines and paths in
  expressions alike; comments, doc links and test code do not count), resolved through the
  parent's `pub use child::...` re-exports.
- **No upward import.** Nothing but the binary's entry (`lib.rs`, `main.rs`) and the command
  layer itself (`commands`, `cli`) imports the command layer.

Crates: every workspace member's `src/` (the daemon's engine package too). Test code is not
counted: `tests.rs` and `*_tests.rs` files and what follows a file's `#[cfg(test)]`.
Run from the repository root: `scripts/check-modules` (`--graph` prints each parent's edges).
"""

import pathlib
import re
import sys

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from check_sizes import code_lines, production_part  # noqa: E402

CRATES = ["protocol/src", "ica-core/src", "replay/src", "daemon/src", "daemon/engine/src", "tests/src"]
# The command layer of a crate: only the entry files and the layer itself may import it.
TOP = {"daemon/src": {"commands", "cli"}}
PATH = re.compile(r"(?<![\w:])(\$?crate|super|self)((?:::\w+)+|(?:::\{))")
GROUP = re.compile(r"(?<![\w:])(\$?crate|super|self)((?:::\w+)*)::\{([^{}]*(?:\{[^{}]*\}[^{}]*)*)\}")


def module_of(root, path):
    """The module path of `path` under the crate `root` (a tuple; () for the crate root)."""
    rel = path.relative_to(root).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] in ("mod", "lib", "main") and (len(parts) > 1 or parts[-1] != "mod"):
        parts = parts[:-1]
    if len(parts) >= 2 and parts[0] == "bin":
        return ("bin",) + tuple(parts[1:])
    return tuple(parts)


def references(lines):
    """Every `crate::`/`super::`/`self::` path in the code, as (head, [segments]); a group
    `a::{b, c::d}` gives one path per member."""
    text = "\n".join(lines)
    out = []
    for m in GROUP.finditer(text):
        head, prefix, body = m.group(1), m.group(2), m.group(3)
        base = [s for s in prefix.split("::") if s]
        for member in re.split(r",(?![^{]*\})", body):
            segs = [s for s in re.findall(r"\w+", member.split(" as ")[0])]
            if segs and segs[0] != "self":
                out.append((head, base + segs))
            else:
                out.append((head, base))
    for m in PATH.finditer(text):
        segs = [s for s in m.group(2).split("::") if s and s != "{"]
        out.append((m.group(1), segs))
    return out


def resolve(here, is_dir_module, head, segs, modules):
    """The module a path names: its longest prefix that is a module (absolute tuple)."""
    if head.endswith("crate"):
        base = ()
    elif head == "self":
        base = here
    else:  # super, maybe repeated
        base = here[:-1]
    while segs and segs[0] == "super":
        base, segs = base[:-1], segs[1:]
    target = base
    for s in segs:
        if target + (s,) in modules:
            target = target + (s,)
        else:
            break
    return target, segs[len(target) - len(base):]


def reexports(modules_text, modules):
    """Per module, the names it re-exports from its children: name -> child module."""
    out = {}
    for mod, lines in modules_text.items():
        names = {}
        for line in lines:
            m = re.match(r"\s*pub(?:\([^)]*\))?\s+use\s+(?:self::)?(\w+)::(.*);", line)
            if not m or mod + (m.group(1),) not in modules:
                continue
            child = mod + (m.group(1),)
            rest = m.group(2)
            for name in re.findall(r"(\w+)(?:\s*[,}]|$)", rest):
                names[name] = child
            for alias in re.findall(r"as\s+(\w+)", rest):
                names[alias] = child
        out[mod] = names
    return out


def crate_edges(root):
    files = {}
    for path in sorted(pathlib.Path(root).rglob("*.rs")):
        if path.name.endswith("tests.rs"):
            continue
        mod = module_of(pathlib.Path(root), path)
        lines = production_part(code_lines(path.read_text()))
        files[mod] = files.get(mod, []) + lines
    modules = set(files)
    for mod in list(modules):
        for k in range(len(mod)):
            modules.add(mod[:k])
    exports = reexports(files, modules)
    edges = set()
    for here, lines in files.items():
        for head, segs in references(lines):
            target, rest = resolve(here, True, head, list(segs), modules)
            # A parent's re-export of its child names the child.
            while rest and rest[0] in exports.get(target, {}):
                target, rest = exports[target][rest[0]], rest[1:]
            if target != here:
                edges.add((here, target))
    return modules, edges


def sibling_edges(edges):
    """Each import as an edge between two children of their common parent."""
    out = {}
    for a, b in edges:
        k = 0
        while k < min(len(a), len(b)) and a[k] == b[k]:
            k += 1
        if k == len(a) or k == len(b):
            continue  # an ancestor or a descendant: not between siblings
        parent = a[:k]
        out.setdefault(parent, set()).add((a[k], b[k]))
    return out


def cycles(nodes_edges):
    """Strongly connected components with more than one node (Tarjan)."""
    graph = {}
    for a, b in nodes_edges:
        graph.setdefault(a, set()).add(b)
        graph.setdefault(b, set())
    index, low, stack, on, out, n = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = n[0]
        n[0] += 1
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
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def main():
    show = "--graph" in sys.argv
    bad = False
    for root in CRATES:
        modules, edges = crate_edges(root)
        name = root.removesuffix("/src")
        for parent, sib in sorted(sibling_edges(edges).items()):
            where = "::".join((name,) + parent)
            if show:
                print(f"{where}: " + ", ".join(f"{a}->{b}" for a, b in sorted(sib)))
            for comp in cycles(sib):
                inner = sorted((a, b) for a, b in sib if a in comp and b in comp)
                print(f"error: {where}: {', '.join(comp)} import each other in a circle: "
                      + ", ".join(f"{a} -> {b}" for a, b in inner), file=sys.stderr)
                bad = True
        for top in sorted(TOP.get(root, ())):
            for a, b in sorted(edges):
                if b[:1] == (top,) and a[:1] not in {(t,) for t in TOP[root]} and a != ():
                    print(f"error: {name}::{'::'.join(a)} imports {name}::{'::'.join(b)}, "
                          "the command layer above it", file=sys.stderr)
                    bad = True
    if bad:
        print("within a parent module its children import one way only, and nothing below "
              "the commands imports them (docs/architecture.md)", file=sys.stderr)
        return 1
    print("modules: no cycle among siblings, no upward import")
    return 0


if __name__ == "__main__":
    sys.exit(main())
