#!/bin/bash
# An ensemble's cost against its direct runs, for two builds of one
# generated model run in turn (BENCHMARKS §4a): each build's `--ensemble`
# harness line gives the ensemble's time and its K direct runs' time
# (each the smallest of `--repeat`); over ROUNDS rounds, the smallest of
# each, per build, and the largest difference to the direct runs.
#
# The direct runs of a build are those of its runtime. Since direct
# integration measures each step's error by halves past its global-error
# bound (BENCHMARKS 10c/10d), a chaotic model's direct runs cost about 3.7x
# DOP853's own evaluations; to compare an ensemble with direct DOP853
# alone, build the second binary against a copy of the runtime where that
# measure is off (`if carried || e.calibrates` in method/direct.rs made
# false: the steps, and so the direct runs' answers, are unchanged) and
# read its direct time as the reference.
#
# usage: scripts/ensemble_ab.sh ROUNDS "HARNESS ARGS" BINARY...
# e.g.   scripts/ensemble_ab.sh 5 "--ensemble 1000 --spread 1e-2 --rtol 1e-8 \
#          --atol 1e-10 --repeat 3 --samples 2" plain/lag-dp after/lag-dp
set -euo pipefail
rounds=$1; args=$2; shift 2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for _ in $(seq "$rounds"); do
  for b in "$@"; do
    # shellcheck disable=SC2086
    "$b" $args 2>&1 | tail -1 | sed -n \
      's/.*for all: \([0-9.]*\) ms.*integrations: \([0-9.]*\) ms; largest difference: \([0-9.e+-]*\);.*/\1 \2 \3/p' \
      >> "$tmp/$(echo "$b" | tr / _)"
  done
done
for b in "$@"; do
  f="$tmp/$(echo "$b" | tr / _)"
  echo "$b: ensemble $(sort -n "$f" | head -1 | cut -d' ' -f1) ms," \
    "direct $(sort -k2 -n "$f" | head -1 | cut -d' ' -f2) ms," \
    "largest difference $(head -1 "$f" | cut -d' ' -f3)"
done
