#!/usr/bin/env bash
# Long libFuzzer runs (make fuzz-long): RUNS executions of each target, shared by JOBS processes
# on one corpus directory. The workers see each other's new inputs through libFuzzer's corpus
# reload (-reload, on by default: every second). A finding in one worker stops the others, so
# it is reported at once rather than after the others' hours.
#
# usage: long_run.sh BIN_DIR LONG_DIR RUNS JOBS MAX_LEN TARGET...
#   BIN_DIR   the fuzz build (its CMakeCache.txt tells whether comparison tracing was on)
#   LONG_DIR  per target: corpus/ (kept between runs), artifacts/, log-N.txt; summary.txt
# Exit status: 0 when every target ran all its executions without a finding, 1 otherwise.
set -uo pipefail

if [ "${BASH_VERSINFO[0]}" -lt 5 ] || { [ "${BASH_VERSINFO[0]}" -eq 5 ] && [ "${BASH_VERSINFO[1]}" -lt 1 ]; }; then
    echo "$0: needs bash 5.1 or later (wait -n -p), this is $BASH_VERSION" >&2
    exit 2
fi
if [ $# -lt 6 ]; then
    echo "usage: $0 BIN_DIR LONG_DIR RUNS JOBS MAX_LEN TARGET..." >&2
    exit 2
fi
bin=$1 long=$2 runs=$3 jobs=$4 max_len=$5
shift 5
for n in "$runs" "$jobs" "$max_len"; do
    if ! [[ $n =~ ^[1-9][0-9]*$ ]]; then
        echo "$0: RUNS, JOBS and MAX_LEN must be positive integers (got '$n')" >&2
        exit 2
    fi
done
if [ "$jobs" -gt "$runs" ]; then
    jobs=$runs # a worker with no executions of its own would only replay the corpus
fi
trace_cmp=$(sed -n 's/^FUZZ_TRACE_CMP:BOOL=//p' "$bin/CMakeCache.txt" 2>/dev/null)
commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
status=0

for t in "$@"; do
    exe=$bin/fuzz_$t
    if [ ! -x "$exe" ]; then
        echo "$0: no fuzz target $exe" >&2
        exit 2
    fi
    work=$long/$t
    mkdir -p "$work/corpus" "$work/artifacts"
    rm -f "$work"/log-*.txt
    stamp=$work/.started
    touch "$stamp"
    echo "== fuzz_$t: $runs executions in $jobs process(es), $(date -u +%FT%TZ)"
    declare -A worker=() share=() rc_of=()
    stopping=
    for j in $(seq 1 "$jobs"); do
        share[$j]=$(( runs / jobs + (j <= runs % jobs ? 1 : 0) ))
        "$exe" -runs="${share[$j]}" -max_len="$max_len" -timeout=10 -print_final_stats=1 \
            -artifact_prefix="$work/artifacts/" "$work/corpus" "tests/fuzz/corpus/$t" \
            > "$work/log-$j.txt" 2>&1 &
        worker[$!]=$j
    done
    while [ ${#worker[@]} -gt 0 ]; do
        wait -n -p finished "${!worker[@]}"
        rc=$?
        if [ -z "${finished:-}" ]; then
            # A worker the shell already reaped (killed by a signal outside this wait): wait for
            # each by pid, which still yields its saved status.
            for p in "${!worker[@]}"; do
                wait "$p"
                rc_of[${worker[$p]}]=$?
                echo "   worker ${worker[$p]} ended (exit ${rc_of[${worker[$p]}]})"
            done
            break
        fi
        rc_of[${worker[$finished]}]=$rc
        echo "   worker ${worker[$finished]} ended (exit $rc)"
        unset "worker[$finished]"
        if [ "$rc" -ne 0 ] && [ ${#worker[@]} -gt 0 ] && [ -z "$stopping" ]; then
            echo "   stopping the other workers"
            stopping=1
            kill "${!worker[@]}" 2>/dev/null
        fi
    done
    unset worker
    for j in $(seq 1 "$jobs"); do
        grep -E "^stat::(number_of_executed|average_exec)|ERROR|PROPERTY|SUMMARY|^Done" \
            "$work/log-$j.txt" | sed "s/^/   [$j] /"
    done
    done_runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work"/log-*.txt |
                awk '{s += $1} END {print s + 0}')
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$work"/log-*.txt |
           awk '{s += $1} END {print s + 0}')
    # Each worker must have exited 0 after its own share; the ones this script stopped after
    # another's failure exit non-zero too, and are reported through that failure.
    short=
    failed=
    for j in $(seq 1 "$jobs"); do
        ran=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/log-$j.txt" | tail -n 1)
        [ "${ran:-0}" -ge "${share[$j]}" ] || short="$short $j"
        [ "${rc_of[$j]:-1}" -eq 0 ] || failed="$failed $j(exit ${rc_of[$j]:-?})"
    done
    new_artifacts=$(find "$work/artifacts" -type f -newer "$stamp" | head -n 3)
    if [ -n "$new_artifacts" ]; then
        result="FINDING: $(echo $new_artifacts)"
        status=1
    elif [ -n "$failed" ]; then
        result="FAILED: worker$failed"
        status=1
    elif [ -n "$short" ]; then
        result="stopped early: worker$short"
        status=1
    else
        result="no finding"
    fi
    unset share rc_of
    echo "$(date -u +%FT%TZ) $commit fuzz_$t max_len=$max_len jobs=$jobs trace_cmp=${trace_cmp:-?} runs=$done_runs exec/s=$rate $result" |
        tee -a "$long/summary.txt"
done
exit $status
