#!/usr/bin/env bash
# make coverage: line and branch coverage (gcovr) of the protocol core from the host test suite,
# with floors CI enforces. Usage: tools/quality/coverage.sh [BUILD_DIR]   (default build/coverage)
#
#   COVERAGE_MIN_LINES / COVERAGE_MIN_BRANCHES   floors in percent (90 / 80), checked for the
#                                                total and for each directory of the core
#   COVERAGE_CMAKE_ARGS                          extra configure arguments (make passes
#                                                -DDFP_PYTHON=<venv python> for the interop tests)
# Output: a per-directory summary (also build/coverage/summary.md), per-file text report,
# HTML in build/coverage/html/index.html.
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build/coverage}
min_lines=${COVERAGE_MIN_LINES:-90}
min_branches=${COVERAGE_MIN_BRANCHES:-80}
jobs=$(nproc 2>/dev/null || echo 2)
core=(dp_slave dpv1 movilink firmware/dfp21b)

# Debian's gcovr 5.2 (a pip-installed gcovr earlier on PATH may be another version).
gcovr=${GCOVR:-/usr/bin/gcovr}
[ -x "$gcovr" ] || gcovr=$(command -v gcovr) || { echo "coverage: gcovr not found"; exit 1; }

# Atomic counters: the replay reads its file on a second thread (sim_host/replay/src/file.c),
# and two threads adding to the same plain counter leave counts gcov prints as negative, which
# gcovr refuses to read.
cmake --preset host -B "$build" -DCMAKE_BUILD_TYPE=Debug \
      "-DCMAKE_C_FLAGS=--coverage -fprofile-update=atomic -O0" -DCMAKE_EXE_LINKER_FLAGS=--coverage \
      ${COVERAGE_CMAKE_ARGS:-} >/dev/null
cmake --build "$build"

# Counters from an earlier run would add up.
find "$build" -name '*.gcda' -delete

# The VM tests run the binaries inside QEMU on a read-only view of this tree: they cannot write
# .gcda files (each binary then reports "profiling: ... Cannot open" on stderr, which the tests
# that compare stderr see as a failure). What they add is SocketCAN, not protocol code: the
# core's SBus paths are exercised on the in-memory CAN bus (tests/sbus) as well.
ctest --test-dir "$build" -j "$jobs" --timeout 300 --output-on-failure -E '(^vm_|_vm$)'

filters=()
for d in "${core[@]}"; do filters+=(--filter "$d/"); done
mkdir -p "$build/html"
"$gcovr" -r . "$build" "${filters[@]}" \
    --json-summary "$build/summary.json" \
    --html-details "$build/html/index.html" \
    --txt - -b
"$gcovr" -r . "$build" "${filters[@]}" --txt - | tail -n +6

python3 - "$build/summary.json" "$min_lines" "$min_branches" "$build/summary.md" "${core[@]}" <<'PY'
import json, sys
path, min_l, min_b, out = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
dirs = sys.argv[5:]
files = json.load(open(path))["files"]
rows = []
tot = [0, 0, 0, 0]
for d in dirs:
    s = [0, 0, 0, 0]
    for f in files:
        if f["filename"].startswith(d + "/"):
            s[0] += f["line_covered"]; s[1] += f["line_total"]
            s[2] += f["branch_covered"]; s[3] += f["branch_total"]
    tot = [a + b for a, b in zip(tot, s)]
    rows.append((d, s))
rows.append(("total", tot))
pct = lambda c, t: 100.0 * c / t if t else 100.0
lines = ["| directory | lines | branches |", "|---|---:|---:|"]
failed = []
for name, (lc, lt, bc, bt) in rows:
    lp, bp = pct(lc, lt), pct(bc, bt)
    lines.append(f"| {name} | {lp:.1f} % ({lc}/{lt}) | {bp:.1f} % ({bc}/{bt}) |")
    if lp < min_l or bp < min_b:
        failed.append(f"{name}: lines {lp:.1f} %, branches {bp:.1f} %")
table = "\n".join(lines)
open(out, "w").write(table + "\n")
print(table)
print(f"floors: lines >= {min_l:g} %, branches >= {min_b:g} % (total and every directory)")
if failed:
    print("coverage: BELOW THE FLOOR: " + "; ".join(failed))
    sys.exit(1)
print("coverage: ok")
PY
