#!/usr/bin/env python3
"""The repository stands on its own: no file points at research notes or directories outside it,
and every section a file cites as "protocol.md §A1.6" (§A = PROFIBUS, §B = the DFP21B card,
§C = MOVILINK/SBus/MOVIDRIVE) exists as a heading in docs/protocol.md.

Usage: check_self_contained.py REPO_ROOT. Prints each finding and "N passed, M failed"."""
import os
import re
import sys

root = sys.argv[1] if len(sys.argv) > 1 else "."
SKIP_DIRS = {".git", "build", "node_modules", "__pycache__", ".pytest_cache"}
SELF = os.path.abspath(__file__)

# Assembled from parts so that this file does not match itself.
OUTSIDE = re.compile("|".join([
    r"\.\./" + "shared",
    "shared/" + "spec",
    "shared/" + "guide",
    r"profibus-dp" + r"\.md",
    r"(?<![\w-])dfp21b" + r"\.md",
    r"(?<![\w-])movidrive" + r"\.md",
    r"dfp21b-manual" + r"-pt",
    r"protocol-sources" + r"\.md",
]))
CITED = re.compile(r"§([ABC]\d+(?:\.\d+)?)")
HEADING = re.compile(r"^#{2,4} ([ABC]\d+(?:\.\d+)?)\b")


def files():
    for d, dirs, names in os.walk(root):
        dirs[:] = [x for x in dirs if x not in SKIP_DIRS and not x.startswith("build")]
        for n in names:
            p = os.path.join(d, n)
            if os.path.abspath(p) == SELF:
                continue
            try:
                with open(p, encoding="utf-8") as f:
                    yield os.path.relpath(p, root), f.read()
            except (UnicodeDecodeError, OSError):
                continue  # binary files (captures, images) cite nothing


passed = failed = 0
protocol = os.path.join(root, "docs", "protocol.md")
headings = set()
if os.path.exists(protocol):
    with open(protocol, encoding="utf-8") as f:
        headings = {m.group(1) for line in f if (m := HEADING.match(line))}
    passed += 1
else:
    print("FAIL docs/protocol.md is missing")
    failed += 1

outside = unresolved = 0
for path, text in files():
    for n, line in enumerate(text.splitlines(), 1):
        if OUTSIDE.search(line):
            print(f"FAIL {path}:{n}: points outside the repository: {line.strip()[:120]}")
            outside += 1
        for m in CITED.finditer(line):
            if path != "docs/protocol.md" and m.group(1) not in headings:
                print(f"FAIL {path}:{n}: cites §{m.group(1)}, which docs/protocol.md does not have")
                unresolved += 1
for bad in (outside, unresolved):
    if bad:
        failed += 1
    else:
        passed += 1
print(f"{passed} passed, {failed} failed")
sys.exit(1 if failed else 0)
