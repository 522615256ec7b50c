#!/usr/bin/env bash
# The cost of keeping the constraints (docs/BENCHMARKS.md §11): every
# example with first-order constraints, both methods, two tolerances, run by
# two lagc binaries side by side (BEFORE: a build without keeping, AFTER:
# with it). Prints one markdown row per case: steps, right-side
# evaluations, the error against `exact`, and the smallest wall time of 20
# solves (`--repeat 20`), before -> after.
# Usage: scripts/keep_cost.sh BEFORE_LAGC AFTER_LAGC [EXAMPLE.lag ...]
set -euo pipefail
before=$1 after=$2
shift 2
examples=("$@")
if [ ${#examples[@]} -eq 0 ]; then
    examples=(examples/{paper,knife_edge,knife_edge_circling,chaplygin_sleigh,rolling_disk,rolling_disk_3d,ball_on_turntable,bead_on_exponential}.lag)
fi
figures() {
    # steps, evaluations, error, wall time (ms) from the summary on stderr
    "$1" run "$2" -- --method "$3" --rtol "$4" --samples 2 --repeat 20 2>&1 >/dev/null |
        awk '/steps:/ { match($0, /steps: [0-9]+/); s = substr($0, RSTART + 7, RLENGTH - 7);
                        match($0, /evaluations: [0-9]+/); e = substr($0, RSTART + 13, RLENGTH - 13);
                        match($0, /wall time: [0-9.]+/); w = substr($0, RSTART + 11, RLENGTH - 11) }
             /exact solution:/ { err = $NF }
             END { printf "%s %s %s %s", s, e, (err == "" ? "-" : err), w }'
}
echo "| model | method | rtol | steps | evaluations | error | wall ms (min of 20) |"
echo "|---|---|---|---|---|---|---|"
for ex in "${examples[@]}"; do
    for method in field direct; do
        for rtol in 1e-6 1e-10; do
            read -r s0 e0 err0 w0 <<<"$(figures "$before" "$ex" "$method" "$rtol")"
            read -r s1 e1 err1 w1 <<<"$(figures "$after" "$ex" "$method" "$rtol")"
            echo "| $(basename "$ex" .lag) | $method | $rtol | $s0 → $s1 | $e0 → $e1 | $err0 → $err1 | $w0 → $w1 |"
        done
    done
done
