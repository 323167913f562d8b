#!/usr/bin/env bash
# Renders the README's pictures into docs/images/ and prints the table of errors and times.
# References: pass the directory of the 256x256 reference EXRs (default ../shared/scenes/refs).
# Usage: bash scripts/gallery.sh [REFS_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
refs=${1:-../shared/scenes/refs}
out=docs/images
mkdir -p "$out"
cargo build --release --locked -q
pm=./target/release/photonmap
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

row() { # name scene args...
    local name=$1 scene=$2
    shift 2
    "$pm" render "scenes/$scene/$scene.toml" -o "$tmp/$name.exr" --png "$out/$name.png" \
        --stats "$tmp/$name.json" --quiet "$@"
    local secs err
    secs=$(python3 -c "import json,sys; print(f\"{json.load(open('$tmp/$name.json'))['wall_seconds']:.1f}\")")
    err=$("$pm" compare "$tmp/$name.exr" "$refs/$scene.exr" --json |
        python3 -c "import json,sys; d=json.load(sys.stdin); print(f\"{d['rmse']:.4f} | {100*d['bias']:+.2f}%\")")
    echo "| $name | \`$*\` | $err | $secs |"
}

echo "| image | flags | RMSE | mean bias | seconds |"
echo "|---|---|---|---|---|"
for s in cornell caustics pointlight furnace; do
    row "$s" "$s"
    [ -f "$refs/$s.png" ] && cp "$refs/$s.png" "$out/ref-$s.png"
done
row cornell-per-channel cornell --color per-channel
row cornell-final-gather cornell --indirect final-gather --spp 16 --final-gather-rays 32
row cornell-no-cache cornell --irradiance-cache false --spp 16
row cornell-box cornell --kernel box
row cornell-gaussian cornell --kernel gaussian
row cornell-20k-photons cornell --photons 20000
row cornell-spp4 cornell --spp 4
row cornell-light-samples cornell --spp 16 --light-samples 4
row cornell-k20 cornell --gather-photons 20
row cornell-path cornell --integrator path
row caustics-k10 caustics --caustic-gather-photons 10
row caustics-depth1 caustics --max-depth 1
row caustics-bvh caustics --accel bvh
row caustics-direct caustics --component direct
row caustics-caustic caustics --component caustic
row caustics-indirect caustics --component indirect
row caustics-emitted caustics --component emitted
