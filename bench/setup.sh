#!/usr/bin/env bash
# Sets up what bench/compare.py needs besides niebla itself:
#  - bench/.venv: a Python virtual environment with mitsuba (3.x, PyPI) and numpy;
#  - an LLVM shared library for Mitsuba's llvm_ad_rgb variant (Debian's libllvm19
#    when apt-get is available and we are root; any LLVM >= 11 works, found by
#    Dr.Jit itself or through DRJIT_LIBLLVM_PATH).
# Idempotent: does nothing that is already done.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
venv="$here/.venv"
python="${PYTHON:-python3}"

if [ ! -x "$venv/bin/python" ]; then
    echo "creating $venv"
    "$python" -m venv "$venv"
fi
if ! "$venv/bin/python" -c "import mitsuba, numpy" 2>/dev/null; then
    "$venv/bin/pip" install --quiet --upgrade pip
    "$venv/bin/pip" install --quiet mitsuba numpy
fi

have_llvm() {
    local f
    for f in /usr/lib/llvm-*/lib/libLLVM*.so* /usr/lib/*-linux-gnu/libLLVM*.so* /usr/local/lib/libLLVM*.so*; do
        [ -e "$f" ] && return 0
    done
    return 1
}
if [ -z "${DRJIT_LIBLLVM_PATH:-}" ] && ! have_llvm; then
    if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
        echo "installing libllvm19 (Mitsuba's LLVM backend needs it)"
        apt-get update -qq && apt-get install -y -qq libllvm19 >/dev/null
    else
        echo "warning: no libLLVM found; install LLVM (e.g. apt-get install libllvm19) or set DRJIT_LIBLLVM_PATH" >&2
    fi
fi

"$venv/bin/python" - <<'EOF'
import drjit as dr, mitsuba as mi
mi.set_variant("llvm_ad_rgb")
scene = mi.load_dict({"type": "scene", "integrator": {"type": "volpath"},
                      "sensor": {"type": "perspective", "film": {"type": "hdrfilm", "width": 8, "height": 8}},
                      "light": {"type": "constant"}})
img = mi.render(scene, spp=1)
lib = next((l.split()[-1] for l in open("/proc/self/maps") if "libLLVM" in l), "?")
print(f"mitsuba {mi.__version__}, drjit {dr.__version__}, variant llvm_ad_rgb works (LLVM: {lib})")
EOF
