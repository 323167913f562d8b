#!/usr/bin/env bash
# The camera stage of two photonmap binaries side by side: each round renders every scene at
# its own size and settings with the old binary, then the new one (so a change in the
# machine's load hits both alike), and prints per scene the median seconds of the `camera`
# stage (from --stats), the ratio new / old, and each binary's last image against the old one
# and, when scenes/refs/NAME.exr (or $REFS/NAME.exr) exists, against that reference.
#
#   bash scripts/camera-compare.sh OLD_BINARY NEW_BINARY [ROUNDS] [SCENE...] [-- render flags]
#
# Defaults: 3 rounds; the Cornell box, the caustics scene, the bunny and the doorway.
# STAGE=NAME compares that stage instead of `camera` (STAGE=wall: the whole render's wall time).
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1
new=$2
rounds=${3:-3}
shift $(($# < 3 ? $# : 3))
scenes=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do
    scenes+=("$1")
    shift
done
[ "${1:-}" = "--" ] && shift
flags=("$@")
[ ${#scenes[@]} -eq 0 ] && scenes=(scenes/cornell/cornell.toml scenes/caustics/caustics.toml
    scenes/bunny/bunny.toml scenes/doorway/doorway.toml)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for round in $(seq 1 "$rounds"); do
    for scene in "${scenes[@]}"; do
        name=$(basename "$scene" .toml)
        for which in old new; do
            bin=$old
            [ "$which" = new ] && bin=$new
            "$bin" render "$scene" -q -o "$out/$name.$which.exr" --stats "$out/$name.$which.$round.json" \
                "${flags[@]}" >/dev/null
        done
    done
    echo "round $round of $rounds done (load average $(cut -d' ' -f1 /proc/loadavg))" >&2
done
printf '%-12s %9s %9s %8s   (%s)\n' scene "old s" "new s" new/old "${STAGE:-camera}"
for scene in "${scenes[@]}"; do
    name=$(basename "$scene" .toml)
    python3 - "$out" "$name" "$rounds" "${STAGE:-camera}" <<'PY'
import json, statistics, sys
out, name, rounds, stage = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
def camera(which):
    times = []
    for r in range(1, rounds + 1):
        stats = json.load(open(f"{out}/{name}.{which}.{r}.json"))
        if stage == "wall":
            times.append(stats["wall_seconds"])
        else:
            times.append(sum(s["seconds"] for s in stats["stages"] if s["name"] == stage))
    return statistics.median(times)
o, n = camera("old"), camera("new")
print(f"{name:<12} {o:9.3f} {n:9.3f} {n / o:8.3f}")
PY
done
for scene in "${scenes[@]}"; do
    name=$(basename "$scene" .toml)
    echo "$name: new against old: $("$new" compare "$out/$name.new.exr" "$out/$name.old.exr")"
    ref=${REFS:-scenes/refs}/$name.exr
    if [ -f "$ref" ]; then
        for which in old new; do
            echo "$name: $which against $ref: $("$new" compare "$out/$name.$which.exr" "$ref")"
        done
    fi
done
