#!/usr/bin/env bash
# Real glTF models from the wild, rendered alone: the 82 GLBs of the `@webxr-input-profiles/assets`
# npm package (VR controllers and hands by their makers: PBR textures, normal maps, glowing LEDs,
# skins, alpha blending), each at 64x64 with `photonmap render model.glb`. Prints one line a model
# (exit status, seconds, the image's mean, the warnings' count) and a summary: how many rendered,
# how many failed, how many came out dark (mean under 0.05, against about 0.85 for a white-sky-lit
# model), and the warnings by kind. Needs npm (a package registry); nothing is kept in the repo.
#
#   bash scripts/gltf-sweep.sh [VERSION (default 1.0.20)]
set -euo pipefail
cd "$(dirname "$0")/.."
version=${1:-1.0.20}
bin=${PHOTONMAP:-target/release/photonmap}
[ -x "$bin" ] || cargo build --release --locked --quiet
command -v npm >/dev/null || { echo "gltf-sweep: needs npm (apt install npm)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
(cd "$work" && npm pack --silent "@webxr-input-profiles/assets@$version" >/dev/null && tar xzf ./*.tgz)
total=0 failed=0 dark=0
: >"$work/warnings"
while IFS= read -r glb; do
    total=$((total + 1))
    name=${glb#"$work/package/dist/profiles/"}
    start=$(date +%s.%N)
    if "$bin" render "$glb" --width 64 --height 64 -o "$work/out.exr" -q 2>"$work/err"; then status=0; else status=$?; fi
    seconds=$(python3 -c "print(f'{$(date +%s.%N) - $start:.1f}')")
    if [ "$status" -ne 0 ]; then
        failed=$((failed + 1))
        echo "FAILED $status ${seconds}s $name: $(tail -1 "$work/err")"
        continue
    fi
    mean=$("$bin" compare "$work/out.exr" "$work/out.exr" | sed -n 's/.*mean \([0-9.e+-]*\) vs.*/\1/p')
    if python3 -c "import sys; sys.exit(0 if float('$mean') < 0.05 else 1)"; then dark=$((dark + 1)); fi
    # Each warning's kind: its text with the file, names and numbers taken out.
    sed -e "s|$work/package/dist/profiles/[^:]*: ||" -e 's/(material [^)]*)/(material M)/' \
        -e 's/materials\[[0-9]*\]/materials[N]/g' -e 's/nodes\[[0-9]*\]/nodes[N]/g' \
        -e 's/[0-9][0-9.e+-]*/#/g' "$work/err" >>"$work/warnings"
    echo "ok ${seconds}s mean $mean warnings $(wc -l <"$work/err") $name"
done < <(find "$work/package/dist/profiles" -name '*.glb' | sort)
echo "== $total models: $((total - failed)) rendered, $failed failed, $dark dark (mean under 0.05)"
echo "== warnings by kind:"
sort "$work/warnings" | uniq -c | sort -rn
