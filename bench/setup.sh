#!/usr/bin/env bash
# Sets up what bench/compare.py needs besides niebla itself:
#  - bench/.venv: a Python virtual environment with mitsuba (3.x, PyPI) and numpy;
#  - an LLVM shared library for Mitsuba's llvm_ad_rgb variant (Debian's libllvm19
#    when apt-get is available and we are root; LLVM 15 fails on fminimum, so
#    19 or newer is required; the
#    scripts in bench/ point Dr.Jit at the newest one through DRJIT_LIBLLVM_PATH).
# Idempotent: does nothing that is already done.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
venv="$here/.venv"
python="${PYTHON:-python3}"

if [ ! -x "$venv/bin/python" ]; then
    echo "creating $venv"
    "$python" -m venv "$venv"
fi
# Pillow writes the PNG figures of docs/ (e.g. docs/fireball_figure.py).
if ! "$venv/bin/python" -c "import mitsuba, numpy, PIL" 2>/dev/null; then
    "$venv/bin/pip" install --quiet --upgrade pip
    "$venv/bin/pip" install --quiet mitsuba numpy pillow
fi

# Dr.Jit's code needs LLVM 19 or newer here (LLVM 15 aborts with "Cannot
# select ... fminimum" on x86); a machine may have older ones installed beside it.
newest_llvm() {
    ls -d /usr/lib/*-linux-gnu/libLLVM-*.so /usr/lib/llvm-*/lib/libLLVM-*.so 2>/dev/null \
        | sed -n 's/.*libLLVM-\([0-9]*\)\.so$/\1 &/p' | awk '$1 >= 19' | sort -n | tail -n 1 | cut -d' ' -f2
}
if [ -z "${DRJIT_LIBLLVM_PATH:-}" ] && [ -z "$(newest_llvm)" ]; then
    if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
        echo "installing libllvm19 (Mitsuba's LLVM backend needs LLVM >= 19)"
        apt-get update -qq && apt-get install -y -qq libllvm19 >/dev/null
    else
        echo "warning: no LLVM >= 19 found; install one (e.g. apt-get install libllvm19) or set DRJIT_LIBLLVM_PATH" >&2
    fi
fi
export DRJIT_LIBLLVM_PATH="${DRJIT_LIBLLVM_PATH:-$(newest_llvm)}"

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

# Blender Cycles as a second peer (`compare.py --peers mitsuba cycles`):
# bench/.venv-cycles with PyPI bpy 5.0.1 (Blender as a Python module, wheels
# for Python 3.11) and numpy; only with --cycles, since the wheel is large.
if [ "${1:-}" = "--cycles" ]; then
    cvenv="$here/.venv-cycles"
    if [ ! -x "$cvenv/bin/python" ]; then
        echo "creating $cvenv"
        "$python" -m venv "$cvenv"
    fi
    if ! "$cvenv/bin/python" -c "import bpy" 2>/dev/null; then
        "$cvenv/bin/pip" install --quiet "bpy==5.0.1" numpy
    fi
    "$cvenv/bin/python" -c "import bpy; print('bpy', bpy.app.version_string, 'works')" 2>/dev/null | tail -n 1
fi
