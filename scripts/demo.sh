#!/usr/bin/env bash
# Installs what is missing, builds photonmap and renders the default scene (the Cornell box)
# to out/cornell.exr with a PNG preview and a JSON report beside it.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
[ -f "$HOME/.cargo/env" ] && . "$HOME/.cargo/env"
mkdir -p out
cargo build --release --locked
./target/release/photonmap render scenes/cornell/cornell.toml \
    -o out/cornell.exr --png out/cornell.png --stats out/cornell.json "$@"
echo "wrote out/cornell.exr, out/cornell.png and out/cornell.json"
