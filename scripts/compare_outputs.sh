#!/bin/bash
# Issue 29: two lagc binaries give the same outputs on every model in
# examples/, tests/data/ (but errors/) and benches/data/ (the generated
# pendulum_50, pendulum_100 and nested_sin_D left out: they take minutes): `lagc build`'s
# src/lib.rs, `lagc derive` text and LaTeX, and build's messages, byte for
# byte. Prints each difference and the count.
# Usage: scripts/compare_outputs.sh OLD_BIN NEW_BIN
set -u
cd "$(dirname "$0")/.."
old=$1
new=$2
out=$(mktemp -d)
n=0
diffs=0
for f in $(find examples tests/data benches/data -name '*.lag' | grep -v '/errors/' |
  grep -v 'pendulum_50\.lag\|pendulum_100\.lag\|nested_sin_' | sort); do
  n=$((n + 1))
  for b in old new; do
    bin=$old
    [ $b = new ] && bin=$new
    rm -rf "$out/crate"
    "$bin" build -o "$out/crate" "$f" >/dev/null 2>"$out/$b.err"
    echo "rc=$?" >>"$out/$b.err"
    cat "$out/crate/src/lib.rs" >"$out/$b.lib" 2>/dev/null
    "$bin" derive "$f" >"$out/$b.derive" 2>&1
    echo "rc=$?" >>"$out/$b.derive"
    "$bin" derive --format latex "$f" >"$out/$b.latex" 2>&1
    echo "rc=$?" >>"$out/$b.latex"
  done
  for k in lib derive latex err; do
    if ! cmp -s "$out/old.$k" "$out/new.$k"; then
      echo "DIFF $k $f"
      diffs=$((diffs + 1))
    fi
  done
done
rm -rf "$out"
echo "models=$n differences=$diffs"
