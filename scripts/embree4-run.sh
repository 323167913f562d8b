#!/usr/bin/env bash
# Builds photonmap's Embree 4 code path (`cfg(embree4)`) against a real Embree 4 library and runs
# the tests that exercise Embree on it, without installing anything system-wide.
#
# Debian 12 ships Embree 3 only, and Debian 13's Embree 4 library needs a newer glibc. The pair
# used here is one Embree release from two registries, so header and library versions match:
#   library: Intel's Embree 4.3.3 release build (glibc >= 2.27), as bundled in the PyPI wheel
#            raybender 4.0.3 (raybender.libs/libembree4-<hash>.so.4 and its libtbb), pinned by hash;
#   headers: Debian 13 ("trixie")'s libembree-dev 4.3.3+dfsg-1 (include/embree4), fetched with a
#            private apt configuration (own source list, lists and cache in a temp dir; the
#            system's apt state is untouched) and unpacked with `dpkg-deb -x`.
# (The embreex 4.4.0 wheel's library has no 4.4.0 headers on any reachable registry: Debian has
# 4.3.3 in trixie and 4.4.1 in sid.) Both are unpacked into target/embree4/embree-4.3.3/
# (include/, lib/), kept there so that re-runs download nothing, and handed to build.rs as
# EMBREE_DIR. build.rs then links that lib/ with an rpath to it (only for EMBREE_DIR builds), so
# the test binaries load that library without LD_LIBRARY_PATH, and it fails the build if the
# library's version is not the headers'. The script then checks that build.rs took the Embree 4
# path and that the test binary resolves libembree4 to the cached copy, and runs, with `cargo
# test`'s profile (opt-level 2) in its target dir (CARGO_TARGET_DIR, default target/, whose
# dependencies the default `cargo test` built; photonmap itself is rebuilt, so run this after
# that step), or in release mode with EMBREE4_RELEASE=1: Embree's unit tests (lib, accel::embree),
# the agreement tests (modules of the one integration-test binary, tests/all.rs: tests/agree_scenes.rs: Embree against the BVH ray by ray on the shipped
# scenes; tests/agree_cutouts.rs: the cut-out filter callbacks) and the stress suite (tests/stress.rs: `photonmap stress --quick`, Embree and the BVH).
#
# Env: EMBREE4_MIRROR (default http://deb.debian.org/debian), EMBREE4_RELEASE=1, CARGO_TARGET_DIR.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
VERSION=4.3.3
WHEEL="raybender==4.0.3"
WHEEL_SHA256=1308889d8a1b913d93c8afb9288e26d685b5060e4c66e03e3bc5de645d29a037
WHEEL_LIBS=raybender.libs
SUITE=trixie
DEB=libembree-dev
DEB_VERSION=4.3.3+dfsg-1
MIRROR=${EMBREE4_MIRROR:-http://deb.debian.org/debian}
CACHE="$ROOT/target/embree4"
EMBREE="$CACHE/embree-$VERSION"

fail() {
    echo "embree4-run: FAILED: $*" >&2
    exit 1
}

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

header_version() {
    awk '/#define RTC_VERSION_(MAJOR|MINOR|PATCH) /{printf "%s%s", sep, $3; sep="."}' "$1/include/embree4/rtcore_config.h"
}

if [ -f "$EMBREE/include/embree4/rtcore.h" ] && [ -e "$EMBREE/lib/libembree4.so" ]; then
    echo "embree4-run: using the cached Embree $VERSION in $EMBREE"
else
    for tool in apt-get dpkg-deb; do
        command -v "$tool" >/dev/null || fail "needs $tool (Debian/Ubuntu)"
    done
    python3 -m pip --version >/dev/null 2>&1 || fail "needs python3 with pip to download the $WHEEL wheel"
    mkdir -p "$CACHE/download"
    # The library: the wheel for CPython 3.11 on manylinux_2_28 whatever the local Python is
    # (only its bundled libraries are used), checked against the pinned hash.
    whl=("$CACHE"/download/raybender-4.0.3-*.whl)
    if [ ! -f "${whl[0]}" ]; then
        echo "embree4-run: downloading the $WHEEL wheel (Embree $VERSION library) from PyPI"
        echo "$WHEEL --hash=sha256:$WHEEL_SHA256" >"$TMP/requirements.txt"
        python3 -m pip download -q --no-deps --only-binary=:all: --platform manylinux_2_28_x86_64 \
            --python-version 3.11 --implementation cp --abi cp311 -d "$TMP/wheel" -r "$TMP/requirements.txt" ||
            fail "pip download $WHEEL (sha256 $WHEEL_SHA256)"
        mv "$TMP"/wheel/*.whl "$CACHE/download/"
        whl=("$CACHE"/download/raybender-4.0.3-*.whl)
    fi
    # The headers: the same release's libembree-dev, exactly this Debian version.
    deb="$CACHE/download/${DEB}_${DEB_VERSION}_amd64.deb"
    if [ ! -f "$deb" ]; then
        mkdir -p "$TMP/lists/partial" "$TMP/cache/archives/partial" "$TMP/sources.list.d" "$TMP/deb"
        echo "deb $MIRROR $SUITE main" >"$TMP/sources.list"
        APT_OPTS=(
            -o "Dir::Etc::SourceList=$TMP/sources.list"
            -o "Dir::Etc::SourceParts=$TMP/sources.list.d"
            -o "Dir::State::Lists=$TMP/lists"
            -o "Dir::Cache=$TMP/cache"
            -o "Debug::NoLocking=1"
            -o "APT::Sandbox::User=$(id -un)"
        )
        echo "embree4-run: downloading $DEB $DEB_VERSION (Embree $VERSION headers) from $SUITE"
        apt-get "${APT_OPTS[@]}" -qq update || fail "apt-get update for $SUITE from $MIRROR"
        (cd "$TMP/deb" && apt-get "${APT_OPTS[@]}" -qq download "$DEB=$DEB_VERSION") ||
            fail "apt-get download $DEB=$DEB_VERSION from $SUITE (is it still $SUITE's version?)"
        mv "$TMP/deb/${DEB}_${DEB_VERSION}_amd64.deb" "$deb" || fail "apt-get did not save ${DEB}_${DEB_VERSION}_amd64.deb"
    fi
    echo "embree4-run: unpacking into $EMBREE"
    part="$EMBREE.partial"
    rm -rf "$part"
    mkdir -p "$part/lib" "$TMP/debroot" "$TMP/wheelroot"
    dpkg-deb -x "$deb" "$TMP/debroot" || fail "dpkg-deb -x $deb"
    [ -f "$TMP/debroot/usr/include/embree4/rtcore.h" ] || fail "$deb has no usr/include/embree4/rtcore.h"
    cp -r "$TMP/debroot/usr/include" "$part/include"
    python3 -m zipfile -e "${whl[0]}" "$TMP/wheelroot" || fail "cannot unzip ${whl[0]}"
    libs=("$TMP/wheelroot/$WHEEL_LIBS"/libembree4*.so.4)
    [ -f "${libs[0]}" ] || fail "${whl[0]} has no $WHEEL_LIBS/libembree4*.so.4"
    # libembree4 finds its libtbb beside it through its own rpath ($ORIGIN).
    cp "$TMP/wheelroot/$WHEEL_LIBS"/*.so* "$part/lib/"
    ln -s "$(basename "${libs[0]}")" "$part/lib/libembree4.so"
    rm -rf "$EMBREE"
    mv "$part" "$EMBREE"
fi

headers=$(header_version "$EMBREE")
[ "$headers" = "$VERSION" ] || fail "the headers in $EMBREE/include are Embree $headers, expected $VERSION"
echo "embree4-run: Embree $headers headers and library $(readlink "$EMBREE/lib/libembree4.so") in $EMBREE"

# The dependencies are those of the default `cargo test` (same features, same profile, whose
# opt-level is 2), so in target/ they are reused: only photonmap is rebuilt, with these bindings.
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$ROOT/target}" EMBREE_DIR="$EMBREE"
unset PHOTONMAP_EMBREE_CHECK_ONLY
cd "$ROOT"
args=(--locked --features embree)
if [ "${EMBREE4_RELEASE:-0}" = 1 ]; then
    args+=(--release)
fi
echo "embree4-run: EMBREE_DIR=$EMBREE cargo test ${args[*]} --lib --test all --no-run"
cargo test "${args[@]}" --lib --test all --no-run ||
    fail "the build against Embree $VERSION failed (see the errors above; a version mismatch is named there)"

# Prove that build.rs took the Embree 4 path and linked embree4 (cargo reports the build script's
# cfgs, env and libraries in its JSON messages, also when its output is cached), and that the
# test binary loads the cached library.
json=$(cargo test "${args[@]}" --lib --test all --no-run --message-format=json 2>/dev/null)
report=$(echo "$json" | grep '"reason":"build-script-executed"' | grep '"package_id":"[^"]*photonmap' | tail -n 1)
[ -n "$report" ] || fail "no build-script report from cargo"
echo "$report" | grep -q '"cfgs":\[[^]]*"embree4"' || fail "build.rs did not select cfg(embree4): $report"
detected=$(echo "$report" | sed -n 's/.*\["PHOTONMAP_EMBREE_VERSION","\([^"]*\)"\].*/\1/p')
[ "$detected" = "$VERSION" ] || fail "build.rs detected Embree '$detected', expected $VERSION"
echo "$report" | grep -q '"linked_libs":\["dylib=embree4"\]' || fail "build.rs does not link embree4: $report"
test_bin=$(echo "$json" | grep '"reason":"compiler-artifact"' | grep '"name":"all"' |
    sed -n 's/.*"executable":"\([^"]*\)".*/\1/p' | tail -n 1)
[ -x "$test_bin" ] || fail "no integration-test binary (all) reported by cargo"
loaded=$(ldd "$test_bin" | awk '/libembree4/{print $3}')
[ "$(dirname "$loaded")" = "$EMBREE/lib" ] ||
    fail "$(basename "$test_bin") loads libembree4 from '${loaded:-nowhere}', not from $EMBREE/lib"
echo "embree4-run: build.rs: cfg(embree4), Embree $detected, linked embree4; tests load $loaded"

echo "embree4-run: Embree's unit tests (accel::embree) against Embree $VERSION"
cargo test "${args[@]}" --lib accel::embree || fail "Embree's unit tests failed against Embree $VERSION"
echo "embree4-run: agreement tests and stress suite against Embree $VERSION"
cargo test "${args[@]}" --test all -- agree_scenes:: agree_cutouts:: stress:: ||
    fail "the agreement tests or the stress suite failed against Embree $VERSION"
echo "embree4-run: OK: Embree $VERSION (headers $SUITE $DEB $DEB_VERSION, library from $WHEEL): unit, agreement and stress tests pass"
