#!/usr/bin/env python3
"""Fails when docs/architecture.md names a function that is not where it says: every link
`[`name`](path)` (or `[`Type::name`](path)`) must point at a file that defines `fn name`, so
the frame path and the training path follow the code. Run from the repository root."""

import pathlib
import re
import sys

DOC = pathlib.Path("docs/architecture.md")
LINK = re.compile(r"\[`([\w:]+)`\]\(([^)]+)\)")


def main():
    text = DOC.read_text()
    bad, seen = [], 0
    for name, target in LINK.findall(text):
        path = (DOC.parent / target).resolve()
        fn = name.split("::")[-1]
        seen += 1
        if not path.is_file():
            bad.append(f"{name}: {target} does not exist")
        elif not re.search(rf"\bfn {re.escape(fn)}\b", path.read_text()):
            bad.append(f"{name}: no `fn {fn}` in {target}")
    for b in bad:
        print(f"error: docs/architecture.md: {b}", file=sys.stderr)
    if bad:
        print("update docs/architecture.md with the code it describes", file=sys.stderr)
        return 1
    print(f"docs/architecture.md: {seen} functions, each where the doc says")
    return 0


if __name__ == "__main__":
    sys.exit(main())
