#!/usr/bin/env bash
# Instructions executed by two photonmap binaries on the same small renders (valgrind's
# callgrind: a count that does not depend on the machine's load, unlike seconds). Prints the
# total per render and the inclusive counts of the main stages; the callgrind files stay in
# OUT_DIR (default /tmp/photonmap-callgrind) for callgrind_annotate.
#
#   bash scripts/callgrind-compare.sh OLD_BINARY NEW_BINARY [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1
new=$2
dir=${3:-/tmp/photonmap-callgrind}
mkdir -p "$dir"
command -v valgrind >/dev/null || { echo "callgrind-compare: valgrind is not installed (apt-get install valgrind)" >&2; exit 1; }
renders=(
    "caustics:scenes/caustics/caustics.toml:--photons 100000 --caustic-photons 30000 --spp 4"
    "cornell:scenes/cornell/cornell.toml:--photons 100000 --spp 8"
)
for r in "${renders[@]}"; do
    IFS=: read -r name scene flags <<<"$r"
    for which in old new; do
        bin=$old
        [ "$which" = new ] && bin=$new
        # shellcheck disable=SC2086
        valgrind --tool=callgrind --callgrind-out-file="$dir/$name.$which.out" "$bin" render "$scene" \
            -o "$dir/$name.$which.exr" --quiet --threads 1 --width 32 --height 32 $flags \
            2>"$dir/$name.$which.log" &
    done
    wait
    for which in old new; do
        total=$(grep -o 'refs: *[0-9,]*' "$dir/$name.$which.log" | tr -dc '0-9')
        printf '%-9s %-4s %15s instructions\n' "$name" "$which" "$total"
        callgrind_annotate --inclusive=yes "$dir/$name.$which.out" 2>/dev/null |
            grep -E 'trace::trace_pass|Irradiance(Cache)?::build|PhotonMap::gather' | head -3 | sed 's/^/    /'
    done
done
