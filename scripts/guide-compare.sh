#!/usr/bin/env bash
# Guided photon emission and portals on and off, at equal time, against a reference: renders
# SCENE with each method, with --photon-guide true and false (and, when the scene has a
# [[portal]], --portals true and false), for SECONDS each and for each seed, and prints every
# run's RMSE, mean bias and map efficiency (seen photons stored per photon emitted, from
# --stats), then per setting the mean RMSE over the seeds and the spread of the mean bias.
# Usage: bash scripts/guide-compare.sh SCENE.toml REFERENCE.exr [SECONDS] [SEEDS]
#   e.g. bash scripts/guide-compare.sh scenes/sunroom/sunroom.toml scenes/refs/sunroom.exr 20 1,2,3,4
# METHODS="photon sppm" (the default) picks the integrators.
set -euo pipefail
cd "$(dirname "$0")/.."
scene=$1 ref=$2 secs=${3:-20} seeds=${4:-1}
cargo build --release --locked -q
bin=./target/release/photonmap
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
portals="true"
grep -q '^\[\[portal\]\]' "$scene" && portals="false true"
for method in ${METHODS:-photon sppm}; do
    for portal in $portals; do
        for guide in false true; do
            tag="$method guide=$guide portals=$portal"
            for seed in ${seeds//,/ }; do
                out="$tmp/run"
                "$bin" render "$scene" --integrator "$method" --time "$secs" --seed "$seed" \
                    --photon-guide "$guide" --portals "$portal" -o "$out.exr" --stats "$out.json" --quiet
                eff=$(python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(' '.join(f\"{k} {v['efficiency']:.4f}\" for k,v in d['photons'].items() if v['emitted']), '| passes', d['passes'])" "$out.json")
                line=$("$bin" compare "$out.exr" "$ref" --json)
                echo "$tag seed $seed ${secs}s: $line | efficiency $eff"
                echo "$tag|$line" >>"$tmp/all"
            done
        done
    done
done
python3 - "$tmp/all" <<'EOF'
import json, sys
rows = {}
for line in open(sys.argv[1]):
    tag, js = line.rstrip("\n").split("|", 1)
    rows.setdefault(tag, []).append(json.loads(js))
print(f"{'setting':40} {'runs':>4} {'mean rmse':>10} {'bias min':>9} {'bias max':>9}")
for tag, rs in rows.items():
    rmse = sum(r["rmse"] for r in rs) / len(rs)
    bias = [100 * r["bias"] for r in rs]
    print(f"{tag:40} {len(rs):4} {rmse:10.5f} {min(bias):+8.2f}% {max(bias):+8.2f}%")
EOF
