#!/bin/bash
# Two builds of one generated model, run in turn: the smallest per-solve
# wall time each reports (`--repeat R` prints `wall_time_s`, the fastest of
# R solves) and the median of the pairs' ratios (after / before). Pairs
# keep the ratio meaningful when the machine's load drifts.
#
# usage: scripts/ab_min_wall.sh BEFORE_BINARY AFTER_BINARY ROUNDS ARGS...
# e.g.   scripts/ab_min_wall.sh before/lag-paper after/lag-paper 15 \
#          --method direct --integrator explicit --rtol 1e-10 --atol 1e-12 --repeat 5000
set -euo pipefail
before=$1; after=$2; rounds=$3; shift 3
wall() { "$@" --quiet --summary json 2>&1 >/dev/null | grep -o '"wall_time_s":[^,]*' | cut -d: -f2; }
for _ in $(seq "$rounds"); do
  echo "$(wall "$before" "$@") $(wall "$after" "$@")"
done | python3 -c "
import sys, statistics
rows = [tuple(map(float, l.split())) for l in sys.stdin if l.strip()]
b = [r[0] for r in rows]; a = [r[1] for r in rows]
print(f'before min {min(b)*1e6:.2f} us, median {statistics.median(b)*1e6:.2f}; '
      f'after min {min(a)*1e6:.2f} us, median {statistics.median(a)*1e6:.2f}; '
      f'median pair ratio {statistics.median([y / x for x, y in rows]):.3f}')
"
