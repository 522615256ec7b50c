#!/bin/bash
# The error at 1001 samples (dense output between steps) of every example
# with an exact solution, both methods, rtol 1e-8, 1e-10, 1e-12 (atol
# rtol/100): one line "MODEL METHOD RTOL ERROR". A sample error orders of
# magnitude above the step ends' is a wrong dense output (the switch back
# from RODAS4 once gave 3.1e-3 at rtol 1e-11 with exit 0).
# Run from the repository root after `cargo build`:
#   scripts/scan_sample_errors.sh | awk '$4 > 20 * $3'
set -u
LAGC=${LAGC:-target/debug/lagc}
for f in $(grep -l "^exact" examples/*.lag); do
  for m in direct field; do
    for r in 1e-8 1e-10 1e-12; do
      a=$(python3 -c "print($r/100)")
      e=$(timeout 120 $LAGC run $f --method $m --rtol $r --atol $a --samples 1001 --summary json 2>&1 >/dev/null | grep -o '"exact_error":[^,]*' | cut -d: -f2)
      echo "$(basename $f) $m $r $e"
    done
  done
done
