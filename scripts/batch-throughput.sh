#!/usr/bin/env bash
# Batch throughput: N frames of a turntable scene rendered by one `photonmap render --frames`
# against N separate invocations (one frame each) at the same settings. Prints wall time,
# frames a minute and the ratio, and for three frames the batch's image against the separate
# render's (identical: the same maps from the same seed).
#
#   bash scripts/batch-throughput.sh scenes/cornell/cornell-turntable.toml [FRAMES] [render flags...]
set -euo pipefail
scene=${1:?usage: batch-throughput.sh SCENE [FRAMES] [render flags...]}
frames=${2:-60}
shift $(( $# >= 2 ? 2 : 1 ))
bin=${PHOTONMAP:-target/release/photonmap}
[ -x "$bin" ] || cargo build --release --quiet
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
last=$((frames - 1))
now() { date +%s.%N; }
t0=$(now)
"$bin" render "$scene" --frames "0-$last" -o "$out/batch_{frame:04}.exr" --stats "$out/batch.json" -q "$@"
t1=$(now)
for f in $(seq 0 "$last"); do
  "$bin" render "$scene" --frames "$f" -o "$out/single_{frame:04}.exr" -q "$@"
done
t2=$(now)
python3 - "$t0" "$t1" "$t2" "$frames" "$out/batch.json" <<'PY'
import json, sys
t0, t1, t2, n = float(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
b, s = t1 - t0, t2 - t1
r = json.load(open(sys.argv[5]))
print(f"frames {n}: one batch {b:.1f} s ({60 * n / b:.1f} frames/min), {n} invocations {s:.1f} s ({60 * n / s:.1f} frames/min), ratio {s / b:.2f}")
print(f"batch: photon stages {r['photon_seconds']:.2f} s in all, camera stages {r['camera_seconds']:.2f} s ({r['camera_seconds'] / n:.3f} s a frame)")
PY
for f in 0 $((frames / 2)) "$last"; do
  printf -v name '%04d' "$f"
  echo "frame $f, batch against separate: $("$bin" compare "$out/batch_$name.exr" "$out/single_$name.exr")"
done
