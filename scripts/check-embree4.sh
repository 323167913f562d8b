#!/usr/bin/env bash
# Type-checks photonmap's Embree 4 code path (`cfg(embree4)`) without installing Embree 4.
#
# Debian 12 ships Embree 3 only. This script fetches Debian 13 ("trixie")'s `libembree-dev`
# (Embree 4.x) with a private apt configuration (its own source list, lists and cache in a temp
# dir, so the system's apt state is untouched), unpacks it with `dpkg-deb -x` into
# target/embree4-headers/ (skipped when already there), then runs
#   EMBREE_DIR=target/embree4-headers/usr PHOTONMAP_EMBREE_CHECK_ONLY=1 cargo check --lib --tests
# with its own CARGO_TARGET_DIR. CHECK_ONLY makes build.rs generate bindings from those headers
# but emit no link directives (the Embree 4 library itself is not installed).
#
# Env: EMBREE4_SUITE (default trixie), EMBREE4_MIRROR (default http://deb.debian.org/debian).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
CACHE="$ROOT/target/embree4-headers"
SUITE=${EMBREE4_SUITE:-trixie}
MIRROR=${EMBREE4_MIRROR:-http://deb.debian.org/debian}

fail() {
    echo "check-embree4: FAILED: $*" >&2
    exit 1
}

if [ -f "$CACHE/usr/include/embree4/rtcore.h" ]; then
    echo "check-embree4: using cached headers in $CACHE"
else
    command -v apt-get >/dev/null && command -v dpkg-deb >/dev/null || fail "needs apt-get and dpkg-deb (Debian/Ubuntu)"
    APT_DIR=$(mktemp -d)
    trap 'rm -rf "$APT_DIR"' EXIT
    mkdir -p "$APT_DIR/lists/partial" "$APT_DIR/cache/archives/partial" "$APT_DIR/sources.list.d" "$APT_DIR/download"
    echo "deb $MIRROR $SUITE main" >"$APT_DIR/sources.list"
    APT_OPTS=(
        -o "Dir::Etc::SourceList=$APT_DIR/sources.list"
        -o "Dir::Etc::SourceParts=$APT_DIR/sources.list.d"
        -o "Dir::State::Lists=$APT_DIR/lists"
        -o "Dir::Cache=$APT_DIR/cache"
        -o "Debug::NoLocking=1"
        -o "APT::Sandbox::User=$(id -un)"
    )
    echo "check-embree4: fetching the $SUITE package lists into $APT_DIR"
    apt-get "${APT_OPTS[@]}" -q update || fail "apt-get update for $SUITE"
    echo "check-embree4: downloading libembree-dev from $SUITE"
    (cd "$APT_DIR/download" && apt-get "${APT_OPTS[@]}" -q download libembree-dev) ||
        fail "apt-get download libembree-dev from $SUITE"
    debs=("$APT_DIR"/download/libembree-dev_*.deb)
    [ -f "${debs[0]}" ] || fail "no libembree-dev .deb was downloaded"
    echo "check-embree4: unpacking $(basename "${debs[0]}")"
    rm -rf "$CACHE.partial"
    mkdir -p "$CACHE.partial"
    dpkg-deb -x "${debs[0]}" "$CACHE.partial" || fail "dpkg-deb -x ${debs[0]}"
    [ -f "$CACHE.partial/usr/include/embree4/rtcore.h" ] ||
        fail "the package has no usr/include/embree4/rtcore.h (is $SUITE's libembree-dev Embree 4?)"
    rm -rf "$CACHE"
    mv "$CACHE.partial" "$CACHE"
fi

CONFIG="$CACHE/usr/include/embree4/rtcore_config.h"
version=$(awk '/#define RTC_VERSION_(MAJOR|MINOR|PATCH) /{printf "%s%s", sep, $3; sep="."}' "$CONFIG")
echo "check-embree4: Embree $version headers in $CACHE/usr/include/embree4"

export CARGO_TARGET_DIR="$ROOT/target/embree4-check"
echo "check-embree4: EMBREE_DIR=$CACHE/usr PHOTONMAP_EMBREE_CHECK_ONLY=1 cargo check --lib --tests"
cd "$ROOT"
export EMBREE_DIR="$CACHE/usr" PHOTONMAP_EMBREE_CHECK_ONLY=1
cargo check --lib --tests --features embree ||
    fail "the cfg(embree4) code path does not type-check against Embree $version (see the errors above)"

# Prove that build.rs really took the Embree 4 path: cargo reports the build script's cfgs, env
# and libraries in its JSON messages (also when the script's output is cached).
report=$(cargo check --lib --tests --features embree --message-format=json 2>/dev/null |
    grep '"reason":"build-script-executed"' | grep '"package_id":"[^"]*photonmap' | tail -n 1)
[ -n "$report" ] || fail "no build-script report from cargo"
echo "$report" | grep -q '"cfgs":\[[^]]*"embree4"' || fail "build.rs did not select cfg(embree4): $report"
detected=$(echo "$report" | sed -n 's/.*\["PHOTONMAP_EMBREE_VERSION","\([^"]*\)"\].*/\1/p')
[ "$detected" = "$version" ] || fail "build.rs detected Embree '$detected', the headers say $version"
echo "$report" | grep -q '"linked_libs":\[\]' ||
    fail "build.rs emitted link directives despite PHOTONMAP_EMBREE_CHECK_ONLY=1: $report"
echo "check-embree4: OK: the cfg(embree4) path type-checks against Embree $detected (build.rs: cfg embree4, no linking)"
