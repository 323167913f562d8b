#!/usr/bin/env bash
# Error against time on the four canonical scenes: runs `photonmap converge` with every method
# at every budget against the 256x256 references and writes docs/converge/<scene>.{csv,svg}
# (and a PNG of each plot when rsvg-convert is installed), printing the tables.
# Usage: bash scripts/converge.sh [REFS_DIR] [BUDGETS] [METHODS]
#   REFS_DIR  directory of the reference EXRs (default ../shared/scenes/refs)
#   BUDGETS   seconds, comma-separated (default 1,2,4,8,16,32)
#   METHODS   comma-separated (default all: photon-rgb,photon-channel,final-gather,sppm,path)
# SCENES="cornell caustics" limits the scenes; OUT=dir changes the output directory.
set -euo pipefail
cd "$(dirname "$0")/.."
refs=${1:-../shared/scenes/refs}
budgets=${2:-1,2,4,8,16,32}
methods=${3:-photon-rgb,photon-channel,final-gather,sppm,path}
out=${OUT:-docs/converge}
mkdir -p "$out"
cargo build --release --locked -q
for s in ${SCENES:-cornell caustics pointlight furnace}; do
    echo "== $s (budgets $budgets s)"
    ./target/release/photonmap converge "scenes/$s/$s.toml" --reference "$refs/$s.exr" \
        --budgets "$budgets" --methods "$methods" --csv "$out/$s.csv" --plot "$out/$s.svg"
    if command -v rsvg-convert >/dev/null; then
        rsvg-convert "$out/$s.svg" -o "$out/$s.png"
    fi
done
