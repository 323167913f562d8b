#!/usr/bin/env bash
# Guided photon emission on and off, at equal time, against a reference: renders SCENE with the
# two-pass photon mapper and with sppm, each with --photon-guide true and false, for SECONDS
# each, and prints RMSE, mean bias, and each map's efficiency (seen photons stored per photon
# emitted, from --stats).
# Usage: bash scripts/guide-compare.sh SCENE.toml REFERENCE.exr [SECONDS]
#   e.g. bash scripts/guide-compare.sh scenes/sunroom/sunroom.toml scenes/refs/sunroom.exr 20
set -euo pipefail
cd "$(dirname "$0")/.."
scene=$1 ref=$2 secs=${3:-20}
cargo build --release --locked -q
bin=./target/release/photonmap
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for method in photon sppm; do
    for guide in false true; do
        out="$tmp/$method-$guide"
        "$bin" render "$scene" --integrator "$method" --time "$secs" --photon-guide "$guide" \
            -o "$out.exr" --stats "$out.json" --quiet
        eff=$(python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(' '.join(f\"{k} {v['efficiency']:.4f}\" for k,v in d['photons'].items() if v['emitted']), '| passes', d['passes'])" "$out.json")
        echo "$method guide=$guide ${secs}s: $("$bin" compare "$out.exr" "$ref") | efficiency $eff"
    done
done
