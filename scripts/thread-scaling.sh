#!/usr/bin/env bash
# Thread scaling of two photonmap binaries side by side: each round runs `photonmap bench
# SCENE --runs 1 --threads 1,N` with the old binary, then the new one, so a change in the
# machine's load hits both alike; prints per scene and binary the median seconds on 1 and N
# threads over the rounds and the speed-up (1-thread median over N-thread median).
#
#   bash scripts/thread-scaling.sh OLD_BINARY NEW_BINARY [ROUNDS] [THREADS] [SCENE...]
#
# Defaults: 5 rounds, N = 2, the Cornell box and the caustics scene at bench's 128x128.
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1
new=$2
rounds=${3:-5}
threads=${4:-2}
shift $(($# < 4 ? $# : 4))
scenes=("$@")
[ ${#scenes[@]} -eq 0 ] && scenes=(scenes/cornell/cornell.toml scenes/caustics/caustics.toml)
out=$(mktemp -d)
for round in $(seq 1 "$rounds"); do
    for scene in "${scenes[@]}"; do
        name=$(basename "$scene" .toml)
        for which in old new; do
            bin=$old
            [ "$which" = new ] && bin=$new
            "$bin" bench "$scene" --runs 1 --threads "1,$threads" --json 2>/dev/null \
                >"$out/$name.$which.$round.json"
        done
    done
    echo "round $round of $rounds done (load average $(cut -d' ' -f1 /proc/loadavg))" >&2
done
python3 - "$out" "$threads" "${scenes[@]}" <<'PY'
import json, os, statistics, sys
out, n = sys.argv[1], int(sys.argv[2])
print(f"{'scene':<12} {'binary':<6} {'1 thread s':>11} {f'{n} threads s':>12} {'speed-up':>9} {'render/raw':>11}")
for scene in sys.argv[3:]:
    name = os.path.basename(scene)[:-5]
    for which in ("old", "new"):
        files = sorted(f for f in os.listdir(out) if f.startswith(f"{name}.{which}."))
        rows = [json.load(open(os.path.join(out, f)))["rows"] for f in files]
        one = statistics.median(r[0]["seconds"] for r in rows)
        many = statistics.median(r[1]["seconds"] for r in rows)
        ratio = statistics.median(r[1]["rays_to_raw_ratio"] for r in rows)
        print(f"{name:<12} {which:<6} {one:>11.3f} {many:>12.3f} {one / many:>9.3f} {ratio:>11.3f}")
PY
