#!/usr/bin/env bash
# Installs Mitsuba 3 (for scripts/mitsuba_reference.py) into a Python venv, idempotently:
#   * Debian's libllvm19 (for the fast llvm_ad_rgb variant; scalar_rgb needs nothing),
#   * a venv at $MITSUBA_VENV (default /work/mitsuba-venv) with mitsuba and numpy.
# Does nothing that is already done. Run as root (apt-get). Usage: bash scripts/mitsuba-setup.sh
set -euo pipefail

VENV="${MITSUBA_VENV:-/work/mitsuba-venv}"
MITSUBA_VERSION="${MITSUBA_VERSION:-3.9.1}"

if ! dpkg-query -W -f='${Status}' libllvm19 2>/dev/null | grep -q "install ok installed"; then
    echo "mitsuba-setup: installing libllvm19 (apt)" >&2
    apt-get install -y libllvm19 || { apt-get update && apt-get install -y libllvm19; }
fi

if [ ! -x "$VENV/bin/python" ]; then
    echo "mitsuba-setup: creating venv $VENV" >&2
    python3 -m venv "$VENV"
fi

if ! "$VENV/bin/python" -c "import mitsuba, numpy, sys; sys.exit(mitsuba.__version__ != '$MITSUBA_VERSION')" 2>/dev/null; then
    echo "mitsuba-setup: installing mitsuba==$MITSUBA_VERSION numpy into $VENV" >&2
    "$VENV/bin/pip" install --quiet "mitsuba==$MITSUBA_VERSION" numpy
fi

"$VENV/bin/python" - <<'PY'
import drjit as dr
import mitsuba as mi
print("mitsuba", mi.__version__)
for v in ("llvm_ad_rgb", "scalar_rgb"):
    try:
        mi.set_variant(v)
        x = mi.Float(1.0) + 1.0  # llvm_ad_rgb compiles this with libLLVM: fails if it is missing
        dr.eval(x)
        print("usable variant:", v)
        break
    except Exception as e:
        print("variant", v, "unavailable:", e)
PY
