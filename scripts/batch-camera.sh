#!/usr/bin/env bash
# The camera stage a frame of a batch, for binaries side by side: each round renders frames
# 0..N-1 of a turntable scene with every binary in turn (so a change in the machine's load hits
# all alike) and prints, per binary, the camera stage's seconds a frame of each round, sorted
# (take the middle one), from --stats.
#
#   bash scripts/batch-camera.sh ROUNDS FRAMES SCENE BINARY...
#   e.g. bash scripts/batch-camera.sh 3 8 scenes/caustics/caustics-turntable.toml old/photonmap new/photonmap
set -euo pipefail
rounds=${1:?usage: batch-camera.sh ROUNDS FRAMES SCENE BINARY...}
frames=$2
scene=$3
shift 3
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for _ in $(seq 1 "$rounds"); do
    for bin in "$@"; do
        "$bin" render "$scene" --frames "0-$((frames - 1))" -o "$out/f_{frame:04}.exr" -q --stats "$out/s.json" >/dev/null
        python3 -c "import json, sys; d = json.load(open(sys.argv[1])); print(sys.argv[2], round(d['camera_seconds'] / int(sys.argv[3]), 4))" \
            "$out/s.json" "$bin" "$frames"
    done
done | sort -k1,1 -k2,2n | awk '{a[$1] = a[$1] " " $2} END {for (k in a) print k ":" a[k]}'
