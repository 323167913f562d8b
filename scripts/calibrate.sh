#!/usr/bin/env bash
# The error estimate against the true error: runs `photonmap converge` (which prints, for every
# render, its own estimate of its RMSE from its passes beside the RMSE against the reference) on
# the four canonical scenes and the five hard ones (and the sunroom with its portal), for the pass-indexed progressive photon mapper
# and the path tracer at several budgets, and writes docs/calibration/<scene>.csv and the table
# docs/calibration/table.md (scripts/calibration_summary.py). The true error is the RMSE against
# the reference less the reference's own noise in quadrature (--reference-noise, from
# scenes/SCENES.md and scenes/refs/<name>.txt); the furnace is judged against its exact 2.
# Usage: bash scripts/calibrate.sh [REFS_DIR] [BUDGETS] [METHODS]
#   REFS_DIR  the canonical references (default ../shared/scenes/refs)
#   BUDGETS   seconds, comma-separated (default 2,5,20)
#   METHODS   default pppm,path (photon-rgb and sppm estimate their noise only: their rows are
#             marked `*`)
# SCENES="cornell sunroom" limits the scenes; OUT=dir changes the output directory.
set -euo pipefail
cd "$(dirname "$0")/.."
refs=${1:-../shared/scenes/refs}
budgets=${2:-2,5,20}
methods=${3:-pppm,path}
out=${OUT:-docs/calibration}
mkdir -p "$out"
cargo build --release --locked -q
# scene  reference  its noise (RMSE)
table="furnace exact 0
cornell $refs/cornell.exr 0.0009
caustics $refs/caustics.exr 0.0048
pointlight $refs/pointlight.exr 0.0090"
for s in sunroom doorway bunny glassknot faraway; do
    noise=$(sed -n 's/^noise RMSE[^:]*: *//p' "scenes/refs/$s.txt")
    table+=$'\n'"$s scenes/refs/$s.exr $noise"
done
# The sunroom with its window declared a portal: the same light, without the heavy photons.
table+=$'\n'"sunroom-portal scenes/refs/sunroom.exr $(sed -n 's/^noise RMSE[^:]*: *//p' scenes/refs/sunroom.txt)"
while read -r s ref noise; do
    case " ${SCENES:-$s} " in *" $s "*) ;; *) continue ;; esac
    echo "== $s (budgets $budgets s, reference noise $noise)"
    if [ "$ref" = exact ]; then
        judge=(--exact 2)
    else
        judge=(--reference "$ref" --reference-noise "$noise")
    fi
    toml=scenes/$s/$s.toml
    [ -f "$toml" ] || toml=$(ls scenes/*/"$s.toml")
    ./target/release/photonmap converge "$toml" "${judge[@]}" \
        --budgets "$budgets" --methods "$methods" --csv "$out/$s.csv"
done <<< "$table"
python3 scripts/calibration_summary.py "$out" > "$out/table.md"
cat "$out/table.md"
