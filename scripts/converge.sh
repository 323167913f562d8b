#!/usr/bin/env bash
# Error against time on the four canonical scenes: runs `photonmap converge` with every method
# at every budget against the 256x256 references and writes docs/converge/<scene>.{csv,svg}
# (and a PNG of each plot when rsvg-convert is installed), printing the tables; other renderers'
# figures from docs/converge/peers.csv are drawn dashed and raced at equal time.
# Usage: bash scripts/converge.sh [REFS_DIR] [BUDGETS] [METHODS]
#   REFS_DIR  directory of the reference EXRs (default ../shared/scenes/refs)
#   BUDGETS   seconds, comma-separated (default 1,2,5,10,20,45: the peers' 5, 20 and 45 s among them)
#   METHODS   comma-separated (default: photon-rgb,photon-channel,final-gather,sppm,path; also
#             photon-default, the two-pass defaults `render --time` runs, and pppm)
# SEED=N sets the renders' seed (default 1). The reference's noise, where its .txt record gives
# it, is passed as --reference-noise.
# SCENES="cornell caustics" limits the scenes (a variant such as sunroom-portal is found beside
# its scene; REF_sunroom_portal=sunroom names its reference); OUT=dir changes the output directory.
set -euo pipefail
cd "$(dirname "$0")/.."
refs=${1:-../shared/scenes/refs}
budgets=${2:-1,2,5,10,20,45}
methods=${3:-photon-rgb,photon-channel,final-gather,sppm,path}
out=${OUT:-docs/converge}
mkdir -p "$out"
cargo build --release --locked -q
for s in ${SCENES:-cornell caustics pointlight furnace}; do
    echo "== $s (budgets $budgets s)"
    # A variant (sunroom-portal) lives beside its scene and shares its reference (REF_sunroom_portal=sunroom).
    toml=scenes/$s/$s.toml
    [ -f "$toml" ] || toml=$(ls scenes/*/"$s.toml")
    ref_var="REF_${s//-/_}"
    ref=${!ref_var:-$s}
    # The reference's own noise, from its record (scripts/mitsuba_reference.py writes it), is
    # taken out of the slope and of the estimate's calibration.
    noise=()
    if [ -f "$refs/$ref.txt" ]; then
        n=$(sed -n 's/^noise RMSE[^:]*: *//p' "$refs/$ref.txt")
        if [ -n "$n" ]; then noise=(--reference-noise "$n"); fi
    fi
    ./target/release/photonmap converge "$toml" --reference "$refs/$ref.exr" "${noise[@]}" \
        --budgets "$budgets" --methods "$methods" --csv "$out/$s.csv" --plot "$out/$s.svg" \
        --peers docs/converge/peers.csv --seed "${SEED:-1}"
    if command -v rsvg-convert >/dev/null; then
        rsvg-convert "$out/$s.svg" -o "$out/$s.png"
    fi
done
