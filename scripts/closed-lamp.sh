#!/usr/bin/env bash
# A point light shut in a closed 5 cm box of zero-thickness walls, in the point-lit Cornell box
# (as a light placed inside a closed lamp mesh would be): every photon stays in the box, and the
# image must be black. Renders it at the defaults with each binary given and prints the wall
# time, the stages' times and the image's mean and RMSE against black: the kd-tree's pruning and
# the leaks of thin walls are what this scene measures (docs/robustness.md).
#
#   bash scripts/closed-lamp.sh [BINARY...]      (default: target/release/photonmap)
set -euo pipefail
cd "$(dirname "$0")/.."
bins=("$@")
[ ${#bins[@]} -eq 0 ] && bins=(target/release/photonmap)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
cp scenes/pointlight/pointlight.obj scenes/pointlight/pointlight.mtl "$out/"
python3 - "$out/pointlight.obj" scenes/pointlight/pointlight.toml <<'PY'
import sys, tomllib
path = sys.argv[1]
# The box, 5 cm wide, about the scene's point light.
centre = tomllib.load(open(sys.argv[2], "rb"))["light"][0]["position"]
h = 0.025
n = sum(1 for line in open(path) if line.startswith("v "))
corners = [(centre[0] + sx * h, centre[1] + sy * h, centre[2] + sz * h)
           for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
with open(path, "a") as f:
    f.write("\no lamp\nusemtl white\n")
    for c in corners:
        f.write("v %f %f %f\n" % c)
    for q in faces:
        a, b, c, d = (n + 1 + i for i in q)
        f.write("f %d %d %d\nf %d %d %d\n" % (a, b, c, a, c, d))
PY
cp scenes/pointlight/pointlight.toml "$out/closed-lamp.toml"
for bin in "${bins[@]}"; do
    "$bin" render "$out/closed-lamp.toml" -q -o "$out/image.exr" --stats "$out/stats.json"
    "$bin" compare "$out/image.exr" --exact 0 --json > "$out/black.json"
    python3 - "$bin" "$out/stats.json" "$out/black.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[2]))
b = json.load(open(sys.argv[3]))
stages = ", ".join(f"{st['name']} {st['seconds']:.2f} s" for st in s["stages"] if st["ran"] and st["seconds"] >= 0.05)
print(f"{sys.argv[1]}: {s['wall_seconds']:.1f} s ({stages}); image mean {b['mean']:.2e}, RMSE {b['rmse']:.2e} against black")
PY
done
