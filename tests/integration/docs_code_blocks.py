#!/usr/bin/env python3
"""The programs shown in the docs are the programs that run: every fenced block of README.md and
docs/*.md preceded by `<!-- example: file examples/NAME.cpp -->` must equal that file, line for line
(the file is built and run by `make test` as example.NAME). And every examples/*.cpp is shown in some
page, so no example goes undocumented.

usage: docs_code_blocks.py [ignored: the path of axon, as every integration script gets]
"""
import difflib
import os
import re
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
MARK = re.compile(r"<!--\s*example:\s*file\s+(\S+)\s*-->")


def marked_blocks(path):
    """(line, file named by the mark, block text) for each marked fenced block of a markdown file."""
    lines = open(path, encoding="utf-8").read().splitlines()
    found, n = [], 0
    while n < len(lines):
        m = MARK.search(lines[n])
        if m and n + 1 < len(lines) and lines[n + 1].startswith("```"):
            end = n + 2
            while end < len(lines) and not lines[end].startswith("```"):
                end += 1
            found.append((n + 1, m.group(1), lines[n + 2:end]))
            n = end
        elif m:
            found.append((n + 1, m.group(1), None))
        n += 1
    return found


def main():
    pages = [os.path.join(ROOT, "README.md")] + sorted(
        os.path.join(ROOT, "docs", f) for f in os.listdir(os.path.join(ROOT, "docs")) if f.endswith(".md"))
    failures, shown = [], set()
    for page in pages:
        for line, name, block in marked_blocks(page):
            where = f"{os.path.relpath(page, ROOT)}:{line}"
            target = os.path.join(ROOT, name)
            if block is None:
                failures.append(f"{where}: the mark for {name} is not followed by a fenced block")
            elif not os.path.isfile(target):
                failures.append(f"{where}: {name} does not exist")
            else:
                want = open(target, encoding="utf-8").read().splitlines()
                if block != want:
                    diff = "\n".join(difflib.unified_diff(want, block, name, where, lineterm="", n=1))
                    failures.append(f"{where}: the block differs from {name}:\n{diff}")
                shown.add(os.path.normpath(target))
    examples = os.path.join(ROOT, "examples")
    for f in sorted(os.listdir(examples)):
        if f.endswith(".cpp") and os.path.normpath(os.path.join(examples, f)) not in shown:
            failures.append(f"examples/{f} is shown in no page (mark a block `<!-- example: file examples/{f} -->`)")
    print(f"{len(shown)} example programs shown in the docs")
    for f in failures:
        print("FAIL:", f, file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
