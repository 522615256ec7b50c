#!/bin/sh
# Generates the three models' crates with lagc (sharing one runtime copy),
# then builds and runs the comparison. Usage, from anywhere:
#   benches/diffsol_vs_rodas4/run.sh [REPEATS] > RESULTS.md
set -e
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
cd "$root"
cargo build --release --quiet
for model in mass_gain_stiff mass_loss_stiff_spring mass_gain_1000; do
    ./target/release/lagc build "examples/$model.lag" -o "$root/target/diffsol-vs-rodas4-models/$model" \
        --runtime "$root/target/diffsol-vs-rodas4-models/lagc-runtime" --force >/dev/null
done
cd "$here"
cargo run --release --quiet -- "${1:-5}"
