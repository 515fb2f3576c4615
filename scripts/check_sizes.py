#!/usr/bin/env python3
"""Fails when the workspace's production code grows past the house's size rules:

- no function over 80 lines, at most 5 over 60 (counted from `fn` to its closing brace);
- no `src/` file over 400 lines (inline tests apart: a file is counted up to its
  `#[cfg(test)]` test module).

Test code is not counted: `tests.rs` (and `*_tests.rs`) files, `tests/` and `benches/` folders, and what follows a
file's `#[cfg(test)]`. Run from the repository root: `scripts/check-sizes` (`--list` prints
every function over 60 lines and every file over 300).
"""

import pathlib
import re
import sys

FN_MAX, FN_LONG, LONG_ALLOWED, FILE_MAX = 80, 60, 5, 400
ROOTS = ["protocol/src", "ica-core/src", "replay/src", "daemon/src", "daemon/engine/src", "tests/src"]
FN = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:const\s+)?(?:async\s+)?(?:unsafe\s+)?(?:extern\s+\"[^\"]*\"\s+)?fn\s+(\w+)")


def code_lines(text):
    """The file's lines with comments, strings and char literals blanked (braces in them
    must not count)."""
    out, i, n = [], 0, len(text)
    buf = []
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            buf.append(" " * (j - i))
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
            buf.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            hashes = re.match(r'r(#*)"', text[i:]).group(1)
            end = text.find('"' + hashes, i + len(hashes) + 2)
            end = n if end < 0 else end + 1 + len(hashes)
            buf.append("".join(ch if ch == "\n" else " " for ch in text[i:end]))
            i = end
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            buf.append("".join(ch if ch == "\n" else " " for ch in text[i:j + 1]))
            i = j + 1
        elif c == "'":
            m = re.match(r"'(\\.|\\u\{[0-9a-fA-F]+\}|[^\\'])'", text[i:i + 12])
            if m:
                buf.append(" " * len(m.group(0)))
                i += len(m.group(0))
            else:  # a lifetime
                buf.append(c)
                i += 1
        else:
            buf.append(c)
            i += 1
    return "".join(buf).split("\n")


def production_part(lines):
    """Lines up to the first `#[cfg(test)]` (the inline tests)."""
    for k, line in enumerate(lines):
        if line.strip().startswith("#[cfg(test)]"):
            return lines[:k]
    return lines


def functions(path, lines):
    """(lines, name, first line) of each function in `lines`."""
    out = []
    for k, line in enumerate(lines):
        m = FN.match(line)
        if not m:
            continue
        depth, opened = 0, False
        for j in range(k, len(lines)):
            for ch in lines[j]:
                if ch == "{":
                    depth, opened = depth + 1, True
                elif ch == "}":
                    depth -= 1
                elif ch == ";" and not opened and depth == 0:
                    break  # a declaration without a body
            else:
                if opened and depth == 0:
                    out.append((j - k + 1, m.group(1), f"{path}:{k + 1}"))
                    break
                continue
            break
    return out


def main():
    listing = "--list" in sys.argv
    fns, files = [], []
    for root in ROOTS:
        for path in sorted(pathlib.Path(root).rglob("*.rs")):
            if path.name.endswith("tests.rs") or "tests" in path.parts[2:]:
                continue
            lines = production_part(code_lines(path.read_text()))
            files.append((len(lines), str(path)))
            fns.extend(functions(path, lines))
    over = [f for f in fns if f[0] > FN_MAX]
    long = [f for f in fns if f[0] > FN_LONG]
    big = [f for f in files if f[0] > FILE_MAX]
    if listing:
        for n, name, at in sorted(long, reverse=True):
            print(f"fn {name}: {n} lines ({at})")
        for n, path in sorted(files, reverse=True):
            if n > 300:
                print(f"file {path}: {n} lines")
    print(f"functions over {FN_MAX} lines: {len(over)}; over {FN_LONG}: {len(long)} "
          f"(at most {LONG_ALLOWED}); files over {FILE_MAX}: {len(big)}; "
          f"{len(fns)} functions in {len(files)} files")
    bad = False
    for n, name, at in over:
        print(f"error: fn {name} is {n} lines (over {FN_MAX}): {at}", file=sys.stderr)
        bad = True
    if len(long) > LONG_ALLOWED:
        for n, name, at in sorted(long, reverse=True):
            print(f"  fn {name}: {n} lines ({at})", file=sys.stderr)
        print(f"error: {len(long)} functions over {FN_LONG} lines (at most {LONG_ALLOWED})", file=sys.stderr)
        bad = True
    for n, path in big:
        print(f"error: {path} is {n} lines before its tests (over {FILE_MAX})", file=sys.stderr)
        bad = True
    if bad:
        print("split by responsibility (see CONVENTIONS.md, size)", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
