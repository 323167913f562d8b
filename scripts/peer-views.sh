#!/usr/bin/env bash
# Many views against a peer at equal time: every frame of a turntable scene rendered by one
# `photonmap render --frames` and by Mitsuba 3's path tracer driven from Python (one process,
# a sensor per frame, scripts/mitsuba_views.py) in the same total time, each scored against
# long Mitsuba references of three frames (first, middle, last; made once and kept in REFDIR).
#
#   bash scripts/peer-views.sh scenes/cornell/cornell-turntable.toml REFDIR [REF_SPP] [render flags...]
#
# Needs the venv of scripts/mitsuba-setup.sh. Prints per frame: RMSE of ours and of Mitsuba
# against the reference, and the reference's own noise (subtract it in quadrature).
set -euo pipefail
scene=${1:?usage: peer-views.sh SCENE REFDIR [REF_SPP] [render flags...]}
refdir=${2:?usage: peer-views.sh SCENE REFDIR [REF_SPP] [render flags...]}
ref_spp=${3:-8192}
shift $(( $# >= 3 ? 3 : 2 ))
py=${MITSUBA_PYTHON:-/work/mitsuba-venv/bin/python}
bin=${PHOTONMAP:-target/release/photonmap}
[ -x "$bin" ] || cargo build --release --quiet
frames=$("$bin" info "$scene" | sed -n 's/^cameras *[^ ]* ([^,]*, frames 0..=\([0-9]*\)).*/\1/p')
[ -n "$frames" ] || { echo "$scene: its first camera has no turntable frames" >&2; exit 1; }
n=$((frames + 1))
check="0,$((n / 2)),$frames"
mkdir -p "$refdir"
missing=""
for f in ${check//,/ }; do
  printf -v name 'ref_%04d.exr' "$f"
  [ -f "$refdir/$name" ] || missing="$missing${missing:+,}$f"
done
if [ -n "$missing" ]; then
  "$py" scripts/mitsuba_views.py "$scene" "$refdir" --frames "$missing" --spp "$ref_spp"
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
t0=$(date +%s.%N)
"$bin" render "$scene" --frames "0-$frames" -o "$out/ours_{frame:04}.exr" -q "$@"
t1=$(date +%s.%N)
ours=$(python3 -c "print(f'{$t1 - $t0:.1f}')")
echo "photonmap: $n frames in $ours s ($(python3 -c "print(f'{60 * $n / ($t1 - $t0):.1f}')") frames/min)"
"$py" scripts/mitsuba_views.py "$scene" "$out" --seconds "$ours"
for f in ${check//,/ }; do
  printf -v id '%04d' "$f"
  noise=$(sed -n 's/.*noise RMSE \([0-9.]*\).*/\1/p' "$refdir/ref_$id.txt")
  a=$("$bin" compare "$out/ours_$id.exr" "$refdir/ref_$id.exr" | awk '{print $2}')
  b=$("$bin" compare "$out/frame_$id.exr" "$refdir/ref_$id.exr" | awk '{print $2}')
  echo "frame $f: RMSE photonmap $a, mitsuba $b (reference noise $noise)"
done
