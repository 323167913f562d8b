#!/usr/bin/env bash
# Scaling on paper: measures on this machine what a render spread over W workers costs — a pass
# of a 4K (3840x2160) pass-indexed progressive render, the start-up of a worker (scene load,
# accelerator, lights), the size of a part and the time to merge parts — and prints the table of
# docs/scale-out.md: wall time and speed-up for 1, 8, 64 and 512 workers, one merge reading every
# part and a tree of merges (fan-in 8), under the assumptions printed with it.
# Usage: bash scripts/scaling.sh [SCENE] [PASSES]   (default scenes/cornell/cornell.toml, 1024)
# Env: BANDWIDTH (bytes/s into a merging node, default 1.25e9: 10 Gb/s), WIDTH, HEIGHT.
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-scenes/cornell/cornell.toml}
passes=${2:-1024}
width=${WIDTH:-3840} height=${HEIGHT:-2160}
bandwidth=${BANDWIDTH:-1.25e9}
cargo build --release --locked -q
bin=./target/release/photonmap
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
args=(--integrator pppm --passes "$passes" --width "$width" --height "$height")
# One pass and two passes: their difference is a pass, what is left of the one-pass part the
# start-up.
for r in 0..1 1..3 3..4; do
    "$bin" render "$scene" "${args[@]}" --pass-range "$r" -o "$dir/part-${r/../-}.exr" \
        --stats "$dir/part-${r/../-}.json" --quiet
done
# --partial: the parts hold 4 of the render's passes.
start=$EPOCHREALTIME
"$bin" merge "$dir"/part-0-1.exr "$dir"/part-1-3.exr --partial -o "$dir/two.exr" 2>/dev/null
two=$(python3 -c "print($EPOCHREALTIME - $start)")
start=$EPOCHREALTIME
"$bin" merge "$dir"/part-*.exr --partial -o "$dir/three.exr" 2>/dev/null
three=$(python3 -c "print($EPOCHREALTIME - $start)")
python3 - "$dir" "$passes" "$width" "$height" "$bandwidth" "$two" "$three" "$(nproc)" <<'PY'
import json, math, os, sys
d, passes, w, h, bandwidth, two, three, cores = sys.argv[1:]
passes, w, h, bandwidth, two, three, cores = int(passes), int(w), int(h), float(bandwidth), float(two), float(three), int(cores)
one = json.load(open(os.path.join(d, "part-0-1.json")))["wall_seconds"]
pair = json.load(open(os.path.join(d, "part-1-3.json")))["wall_seconds"]
per_pass = pair - one
startup = max(one - per_pass, 0.0)
size = os.path.getsize(os.path.join(d, "part-1-3.exr"))
merge_part = three - two        # reading and adding one more part (the output written once)
merge_fixed = max(two - 2 * merge_part, 0.0)
print(f"measured on this machine ({cores} cores), {w}x{h}, pppm defaults (100k + 30k photons, 4 spp a pass):")
print(f"  a pass {per_pass:.1f} s, start-up {startup:.1f} s, a part {size / 1e6:.0f} MB, "
      f"merge {merge_part:.2f} s a part + {merge_fixed:.2f} s (writing the image)")
print(f"  assumed: workers like this machine, {passes} passes split evenly, parts {size / 1e6:.0f} MB each "
      f"whatever their pass count, {bandwidth * 8 / 1e9:.0f} Gb/s into a merging node, tree fan-in 8\n")
print("| workers | passes each | render s | one merge s | tree merge s | wall s (the faster merge) | speed-up | bytes moved (tree) |")
print("|---|---|---|---|---|---|---|---|")
base = None
for workers in [1, 8, 64, 512]:
    each = math.ceil(passes / workers)
    render = startup + each * per_pass
    fetch = size / bandwidth + merge_part
    # One process renders every pass and writes the image itself: no merge.
    flat = merge_fixed + workers * fetch if workers > 1 else 0.0
    # A tree of merges, fan-in 8: each level's merges run side by side, each reading 8 parts
    # and writing one (a part, or at the top the image: merge_fixed either way).
    levels, tree, moved, count = 0, 0.0, 0.0, workers
    while count > 1:
        fan = min(8, count)
        tree += fan * fetch + merge_fixed
        moved += count * size
        count = math.ceil(count / 8)
        levels += 1
    wall = render + (min(flat, tree) if workers > 1 else 0.0)
    base = base or wall
    print(f"| {workers} | {each} | {render:.0f} | {flat:.0f} | {tree:.0f} ({levels} levels) | {wall:.0f} | {base / wall:.1f}x | {moved / 1e9:.1f} GB |")
PY
