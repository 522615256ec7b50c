#!/bin/bash
# Issue 29, symbolic work that scales with depth: wall and user time of
# `lagc check` and `lagc derive` (and derive's output size) on sin nested D
# deep around q1*q2' and on the N-link pendulum, for each lagc binary given.
# Usage: scripts/bench_depth.sh BIN [BIN ...]   (writes models with
# scripts/gen_nested.py and scripts/gen_pendulum.py into benches/data/)
set -e
cd "$(dirname "$0")/.."
python3 scripts/gen_nested.py 60 120 >/dev/null
python3 scripts/gen_pendulum.py 50 100 >/dev/null
printf "%-28s %-8s %-22s %10s %10s %12s\n" binary command model wall_s user_s derive_bytes
for model in nested_sin_60 nested_sin_120 pendulum_50 pendulum_100; do
  for bin in "$@"; do
    for cmd in check derive; do
      bytes=$(/usr/bin/time -o /tmp/bench_depth.time -f "%e %U" "$bin" $cmd benches/data/$model.lag 2>/dev/null | wc -c)
      times=$(cat /tmp/bench_depth.time)
      [ "$cmd" = check ] && bytes=-
      printf "%-28s %-8s %-22s %10s %10s %12s\n" "$(basename $(dirname $(dirname $bin)))/$(basename $bin)" $cmd $model $times $bytes
    done
  done
done
