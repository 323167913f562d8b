#!/usr/bin/env bash
# Images of two photonmap binaries on the same renders: every integrator and the main photon
# mapping modes on the four scenes at 32x32 with a fixed seed, on the default accelerator
# (Embree when built with it; tests/golden.rs covers the BVH). Says for each render whether the
# two EXRs are byte-identical, and if not, the new image's RMSE and mean against the old.
#
#   bash scripts/image-compare.sh OLD_BINARY NEW_BINARY [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1
new=$2
dir=${3:-/tmp/photonmap-image-compare}
mkdir -p "$dir"
common=(--quiet --width 32 --height 32 --seed 7)
modes=(
    "photon:--photons 20000 --caustic-photons 6000 --spp 2"
    "per-channel:--photons 20000 --caustic-photons 6000 --spp 2 --color per-channel"
    "final-gather:--photons 20000 --caustic-photons 6000 --spp 1 --indirect final-gather --final-gather-rays 4"
    "sppm:--integrator sppm --passes 3 --photons 5000 --caustic-photons 2000 --spp 2"
    "path:--integrator path --spp 4"
)
same=0
differ=0
for scene in cornell caustics pointlight furnace; do
    for m in "${modes[@]}"; do
        name=${m%%:*}
        read -r -a flags <<<"${m#*:}"
        "$old" render "scenes/$scene/$scene.toml" -o "$dir/$scene-$name.old.exr" "${common[@]}" "${flags[@]}"
        "$new" render "scenes/$scene/$scene.toml" -o "$dir/$scene-$name.new.exr" "${common[@]}" "${flags[@]}"
        if cmp -s "$dir/$scene-$name.old.exr" "$dir/$scene-$name.new.exr"; then
            printf '%-11s %-13s identical\n' "$scene" "$name"
            same=$((same + 1))
        else
            printf '%-11s %-13s differs: %s\n' "$scene" "$name" \
                "$("$new" compare "$dir/$scene-$name.new.exr" "$dir/$scene-$name.old.exr")"
            differ=$((differ + 1))
        fi
    done
done
echo "$same identical, $differ different"
