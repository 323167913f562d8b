#!/usr/bin/env bash
# Installs what photonmap needs on Debian or Ubuntu, and only what is missing: Embree (headers +
# library), libclang for bindgen, pkg-config and a C toolchain for linking; with `--test`, also
# Slurm and munge (slurmctld, slurmd, sbatch: the scale-out test, tests/slurm.rs, runs a
# one-node cluster). Idempotent; when
# nothing is missing it only queries dpkg and returns in well under a second.
set -euo pipefail

packages=(libembree-dev libclang-dev pkg-config build-essential)
if [ "${1:-}" = "--test" ]; then
    packages+=(slurm-wlm munge)
fi

missing=()
for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$p")
    fi
done

if ((${#missing[@]})); then
    echo "setup: installing ${missing[*]}" >&2
    sudo=()
    if [ "$(id -u)" -ne 0 ]; then
        command -v sudo >/dev/null || { echo "setup: need root (or sudo) to install ${missing[*]}" >&2; exit 1; }
        sudo=(sudo)
    fi
    export DEBIAN_FRONTEND=noninteractive
    "${sudo[@]}" apt-get update -qq
    "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null && [ -f "$HOME/.cargo/env" ]; then
    # shellcheck disable=SC1091
    . "$HOME/.cargo/env"
fi
if ! command -v cargo >/dev/null; then
    echo "setup: no Rust toolchain (cargo) on PATH; install one with rustup (Rust >= 1.82)" >&2
    exit 1
fi
