#!/usr/bin/env bash
# Speed of two photonmap binaries side by side: `photonmap bench --json` of each, alternated
# round by round (so a change in the machine's load hits both alike), then the median seconds
# per scene and integrator, the ratio new / old, and the median photons/s and rays/s.
#
#   bash scripts/bench-compare.sh OLD_BINARY NEW_BINARY [ROUNDS] [-- extra bench flags]
#
# Example (the comparison of the integrator redesign):
#   git worktree add /tmp/old <commit> && (cd /tmp/old && cargo build --release)
#   cargo build --release
#   bash scripts/bench-compare.sh /tmp/old/target/release/photonmap target/release/photonmap 5
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1
new=$2
rounds=${3:-5}
shift $(($# < 3 ? $# : 3))
[ "${1:-}" = "--" ] && shift
extra=("$@")
out=$(mktemp -d)
cases=(
    "cornell:scenes/cornell/cornell.toml:--integrator photon"
    "caustics:scenes/caustics/caustics.toml:--integrator photon"
    "caustics-fg:scenes/caustics/caustics.toml:--indirect final-gather --final-gather-rays 8 --spp 8"
    "cornell-sppm:scenes/cornell/cornell.toml:--integrator sppm --passes 8"
    "cornell-path:scenes/cornell/cornell.toml:--integrator path --spp 256"
)
for round in $(seq 1 "$rounds"); do
    for c in "${cases[@]}"; do
        IFS=: read -r name scene flags <<<"$c"
        for which in old new; do
            bin=$old
            [ "$which" = new ] && bin=$new
            # shellcheck disable=SC2086
            "$bin" bench "$scene" --runs 1 --threads 1 --width 64 --height 64 --raw-rays 20000 \
                $flags "${extra[@]}" --json 2>/dev/null >"$out/$name.$which.$round.json"
        done
    done
    echo "round $round of $rounds done" >&2
done
python3 - "$out" "$rounds" <<'EOF'
import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
names = sorted({p.split('.')[0] for p in __import__('os').listdir(out)})
print(f"{'case':<14} {'old s':>8} {'new s':>8} {'new/old':>8} {'old photons/s':>14} {'new photons/s':>14} {'old rays/s':>11} {'new rays/s':>11}")
for n in names:
    def med(which, key):
        return statistics.median(json.load(open(f"{out}/{n}.{which}.{r}.json"))["rows"][0][key] for r in range(1, rounds + 1))
    o, w = med("old", "seconds"), med("new", "seconds")
    print(f"{n:<14} {o:8.3f} {w:8.3f} {w / o:8.3f} {med('old', 'photons_traced_per_second'):14.0f} {med('new', 'photons_traced_per_second'):14.0f} {med('old', 'rays_per_second'):11.0f} {med('new', 'rays_per_second'):11.0f}")
EOF
