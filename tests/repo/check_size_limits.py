#!/usr/bin/env python3
"""Files and functions a reader can hold: no source file of the product over 800 lines, no C
function of the protocol core, the board port and the host libraries and programs over 80 lines
(lizard's length: signature to closing brace).

Tests are outside the file limit (a test file is a list of cases, read one case at a time);
generated tables are outside it too (they are data, regenerated and diffed by ctest).

Usage: check_size_limits.py REPO_ROOT. Prints each violation and "N passed, M failed"."""
import os
import sys

try:
    import lizard
except ImportError:
    print("check_size_limits: the lizard module is missing (make deps-python installs it)")
    sys.exit(1)

root = sys.argv[1] if len(sys.argv) > 1 else "."
FILE_LIMIT = 800
FUNCTION_LIMIT = 80
PRODUCT_DIRS = ["dp_slave", "dpv1", "movilink", "firmware", "hal", "sim_host", "tools", "python"]
FUNCTION_DIRS = ["dp_slave", "dpv1", "movilink", "firmware", "hal", "sim_host"]
SOURCE_EXT = (".c", ".h", ".lua", ".js", ".py")
FUNCTION_EXT = (".c", ".h")
GENERATED = {
    "sim_host/movidrive/src/movidrive_params.c",
    "sim_host/movidrive/src/movidrive_names_table.c",
    "tools/wireshark/movidrive_params.lua",
}


def sources(dirs, exts):
    for top in dirs:
        for d, subdirs, names in os.walk(os.path.join(root, top)):
            subdirs[:] = [s for s in subdirs if s not in ("__pycache__", "build")]
            for n in sorted(names):
                rel = os.path.relpath(os.path.join(d, n), root)
                if n.endswith(exts) and rel not in GENERATED:
                    yield rel


passed = failed = 0
long_files = []
for rel in sources(PRODUCT_DIRS, SOURCE_EXT):
    with open(os.path.join(root, rel), encoding="utf-8", errors="replace") as f:
        n = sum(1 for _ in f)
    if n > FILE_LIMIT:
        long_files.append((rel, n))
for rel, n in long_files:
    print(f"FAIL {rel}: {n} lines (limit {FILE_LIMIT})")
failed, passed = (failed + 1, passed) if long_files else (failed, passed + 1)

long_functions = []
for rel in sources(FUNCTION_DIRS, FUNCTION_EXT):
    info = lizard.analyze_file(os.path.join(root, rel))
    for fn in info.function_list:
        if fn.length > FUNCTION_LIMIT:
            long_functions.append((rel, fn.start_line, fn.name, fn.length))
for rel, line, name, length in long_functions:
    print(f"FAIL {rel}:{line}: {name} is {length} lines (limit {FUNCTION_LIMIT})")
failed, passed = (failed + 1, passed) if long_functions else (failed, passed + 1)

print(f"{passed} passed, {failed} failed")
sys.exit(1 if failed else 0)
