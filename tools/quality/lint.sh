#!/usr/bin/env bash
# make lint: cppcheck and clang-tidy over the protocol core and sim_host/, with the committed
# configurations (.clang-tidy, sim_host/.clang-tidy, tools/quality/cppcheck-suppressions.txt).
# Uses the compile_commands.json of a host configuration (the flags the code is built with).
# Exit 1 on any finding. Usage: tools/quality/lint.sh [BUILD_DIR]   (default build/lint)
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build/lint}
jobs=$(nproc 2>/dev/null || echo 2)

for tool in cppcheck clang-tidy python3 cmake; do
    command -v "$tool" >/dev/null || { echo "lint: $tool not found (make deps-apt)"; exit 1; }
done

# Directories under the gate (LINT_DIRS overrides, e.g. to try tests/). firmware/board/ is
# cross-only and not in the host database.
read -r -a dirs <<<"${LINT_DIRS:-dp_slave dpv1 movilink firmware/dfp21b hal sim_host}"

# Configure only (no build): the database follows the current CMakeLists. The LCM message
# types are generated (lcm-gen) so that the sources including them parse; generated code is
# not ours and stays out of the file list (it lives under the build directory). Without
# link-time optimisation: clang-tidy refuses GCC's -fno-fat-lto-objects, and the checks read
# the sources, not how they are linked.
cmake --preset host -B "$build" -DCMAKE_INTERPROCEDURAL_OPTIMIZATION_RELWITHDEBINFO=OFF >/dev/null
cmake --build "$build" --target dfp_lcm_generate dfp_http_www >/dev/null
db="$build/compile_commands.json"

# Sources of those directories that the host build compiles (a file compiled into two targets
# is checked once).
mapfile -t files < <(python3 - "$db" "${dirs[@]}" <<'PY'
import json, os, sys
db, dirs = sys.argv[1], sys.argv[2:]
root = os.getcwd()
seen = []
for e in json.load(open(db)):
    f = os.path.relpath(os.path.join(e["directory"], e["file"]), root)
    if any(f.startswith(d + "/") for d in dirs) and f not in seen:
        seen.append(f)
print("\n".join(sorted(seen)))
PY
)
echo "lint: ${#files[@]} source files in ${dirs[*]}"

status=0

echo "lint: cppcheck $(cppcheck --version | awk '{print $2}')"
filters=()
for d in "${dirs[@]}"; do filters+=("--file-filter=$d/*"); done
if ! cppcheck --project="$db" "${filters[@]}" --enable=warning,style,performance,portability \
        --library=posix --inline-suppr \
        --suppressions-list=tools/quality/cppcheck-suppressions.txt \
        --error-exitcode=1 --quiet -j "$jobs" \
        --template='{file}:{line}:{column}: {severity}: {message} [cppcheck:{id}]'; then
    status=1
fi

echo "lint: clang-tidy $(clang-tidy --version | awk '/version/ {print $NF; exit}')"
log=$(mktemp)
trap 'rm -f "$log"' EXIT
# clang-tidy exits non-zero on any finding (WarningsAsErrors: '*') and on a file it cannot parse.
if ! printf '%s\n' "${files[@]}" |
        xargs -P "$jobs" -n 1 clang-tidy -p "$build" --quiet >"$log" 2>&1; then
    grep -vE '^[0-9]+ warnings? (and [0-9]+ errors? )?generated\.$|^Suppressed [0-9]+ warnings|^Use -header-filter|^Use -system-headers' "$log" || true
    echo "lint: clang-tidy: $(grep -cE '(warning|error):' "$log") findings"
    status=1
fi

if [ "$status" = 0 ]; then
    echo "lint: clean"
else
    echo "lint: FAILED"
fi
exit "$status"
