#!/usr/bin/env bash
# Installs what is missing, then runs the whole test suite: formatting, lints, docs, every test with
# Embree (the default), the ray-caster-facing ones without it, and the Embree-facing tests run on
# the Embree 4 code path against an Embree 4 library kept in target/ (scripts/embree4-run.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --test
[ -f "$HOME/.cargo/env" ] && . "$HOME/.cargo/env"

# Each step says how long the run has taken so far (to see what the suite's time goes to).
start=$SECONDS
step() { printf '\n== %s (at %d min %02d s)\n' "$*" $(((SECONDS - start) / 60)) $(((SECONDS - start) % 60)) >&2; }

step "format"
cargo fmt --all -- --check
step "lints (Embree on, then off)"
cargo clippy --all-targets --locked -- -D warnings
cargo clippy --all-targets --locked --no-default-features -- -D warnings
step "docs (no broken or ambiguous links)"
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --locked
# Without Embree the pure-Rust BVH casts every ray. The unit tests run in full; of the
# integration tests, the modules where the ray caster decides (agreement with brute force and
# between backends, the stress suite, the command line, bad and fuzzed input, golden images,
# batches and merges). The rest (progressive means, textures, cutouts, guiding, ...) render
# through the same code whichever backend casts, and run in the Embree build below: running
# them twice took some 4 minutes of a suite whose budget is 15.
step "tests without Embree (pure-Rust BVH only)"
# Both test binaries built by one cargo, so that the unit tests' build runs beside the
# library's instead of after it (29 s less in a fresh clone on 2 cores).
cargo test --locked --no-default-features --lib --test all --no-run
cargo test --locked --no-default-features --lib
cargo test --locked --no-default-features --test all -- \
    agree_ stress:: commands:: bad_input:: fuzz_inputs:: golden:: batch:: merge::
step "fuzz targets compile (run them with scripts/fuzz.sh)"
# The main target dir: the dependencies checked by clippy above are reused.
CARGO_TARGET_DIR=target cargo check --locked --manifest-path fuzz/Cargo.toml
step "tests with Embree (the default build)"
cargo test --locked
# Last: it rebuilds photonmap (only) in target/ against Embree 4.
step "Embree 4: unit, agreement and stress tests against Intel's Embree 4.3.3 library"
bash scripts/embree4-run.sh
step "done"
