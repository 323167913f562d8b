#!/usr/bin/env bash
# Coverage-guided fuzzing of the scene-file, OBJ, MTL and glTF loaders with libFuzzer (cargo fuzz):
# each target loads the Cornell box with one of its files replaced by the fuzzer's bytes (gltf: the
# small glTF of tests/data/gltf/, its JSON or GLB replaced) and
# fails on a panic, an unsound scene, or an error that is not one line naming a file.
#
# Usage: bash scripts/fuzz.sh [SECONDS_PER_TARGET (default 60)] [TARGET...]
#   targets: scene_toml obj mtl gltf (default: all four)
#
# Needs a nightly toolchain (rustup) for the sanitizer flags; installs cargo-fuzz from crates.io
# when it is missing. Seeds: the shipped Cornell file of the target's kind (gltf: tests/data/gltf/quad.gltf and
# scenes/boxtextured/BoxTextured.gltf) and every regression
# input of that kind in tests/data/fuzz/. The growing corpus stays in fuzz/corpus/<target>/
# (not committed). A crash lands in fuzz/artifacts/<target>/: minimise it with
# `cargo +nightly fuzz tmin <target> <file>` and add it to tests/data/fuzz/ as
# <name>.{toml,obj,mtl}, where tests/fuzz_inputs.rs replays it in CI.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -f "$HOME/.cargo/env" ] && . "$HOME/.cargo/env"
secs=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(scene_toml obj mtl gltf)

rustup run nightly rustc --version >/dev/null 2>&1 ||
    { echo "fuzz: needs the nightly toolchain (rustup toolchain install nightly)" >&2; exit 1; }
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked

seeds=$(mktemp -d)
trap 'rm -rf "$seeds"' EXIT
status=0
for t in "${targets[@]}"; do
    case $t in
        scene_toml) ext=toml ;;
        obj) ext=obj ;;
        mtl) ext=mtl ;;
        gltf) ext=gltf ;;
        *) echo "fuzz: unknown target $t (scene_toml, obj, mtl, gltf)" >&2; exit 2 ;;
    esac
    mkdir -p "$seeds/$t" "fuzz/corpus/$t"
    if [ "$t" = gltf ]; then
        # The quad, and the textured box whose image and buffer are data: URIs (a file alone).
        cp tests/data/gltf/quad.gltf scenes/boxtextured/BoxTextured.gltf "$seeds/$t/"
    else
        cp "scenes/cornell/cornell.$ext" "$seeds/$t/"
    fi
    cp tests/data/fuzz/*."$ext" "$seeds/$t/" 2>/dev/null || true
    echo "== fuzz $t for $secs s"
    # -dict-free, one job; -max_len leaves room for whole scene files.
    cargo +nightly fuzz run "$t" "fuzz/corpus/$t" "$seeds/$t" -- \
        -max_total_time="$secs" -max_len=65536 -timeout=10 -print_final_stats=1 || status=1
done
exit $status
