#!/usr/bin/env bash
# Installs what is missing, then runs the whole test suite: formatting, lints, docs, every test with
# Embree (the default) and without it, and a type-check of the Embree 4 code path against
# Debian 13's headers.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
[ -f "$HOME/.cargo/env" ] && . "$HOME/.cargo/env"

step() { printf '\n== %s\n' "$*" >&2; }

step "format"
cargo fmt --all -- --check
step "lints (Embree on, then off)"
cargo clippy --all-targets --locked -- -D warnings
cargo clippy --all-targets --locked --no-default-features -- -D warnings
step "docs (no broken or ambiguous links)"
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --locked
step "tests without Embree (pure-Rust BVH only)"
cargo test --locked --no-default-features
step "fuzz targets compile (run them with scripts/fuzz.sh)"
# The main target dir: the dependencies checked by clippy above are reused.
CARGO_TARGET_DIR=target cargo check --locked --manifest-path fuzz/Cargo.toml
if [ -f scripts/check-embree4.sh ]; then
    step "Embree 4 code path type-check"
    bash scripts/check-embree4.sh
fi
step "tests with Embree (the default build)"
cargo test --locked
