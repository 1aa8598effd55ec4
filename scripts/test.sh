#!/usr/bin/env bash
# The project's one test command (README.md). Installs what the tests need on
# a fresh Debian machine, then runs every test of the workspace.
#   NIEBLA_SLOW_TESTS=1 bash scripts/test.sh   also runs the slow convergence checks.
set -euo pipefail
cd "$(dirname "$0")/.."

# The OpenVDB oracle tests generate their files with the reference library
# (Debian's python3-openvdb), called through the system python.
if ! /usr/bin/python3 -c "import openvdb" 2>/dev/null && ! /usr/bin/python3 -c "import pyopenvdb" 2>/dev/null; then
  if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
    echo "installing python3-openvdb and libopenvdb-tools (needed by the VDB reader tests)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-openvdb libopenvdb-tools >/dev/null
  else
    echo "warning: python3-openvdb is missing and cannot be installed here; the VDB oracle tests will fail" >&2
  fi
fi

# The report of `niebla compare` is opened in headless Chromium
# (crates/niebla-cli/tests/compare_report.rs; skipped there without it).
if [ ! -x /usr/bin/chromium ]; then
  if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
    echo "installing chromium (opens the compare report in a headless browser)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
  else
    echo "warning: /usr/bin/chromium is missing and cannot be installed here; the compare report is not opened in a browser" >&2
  fi
fi

# Python virtual environments (the denoiser's and the Python package's) need
# Debian's python3-venv.
if ! python3 -c "import ensurepip" >/dev/null 2>&1; then
  if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
    echo "installing python3-venv (the Python tests and the denoiser run in virtual environments)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv >/dev/null
  fi
fi

# Denoising (`--denoise`, niebla.denoise) loads Intel Open Image Denoise at
# run time; its CPU library comes from the PyPI wheel `pyoidn`, installed into
# a virtual environment of its own (.venv-oidn, reused by later runs). The
# denoising tests then must find it (NIEBLA_REQUIRE_OIDN).
oidn_venv=.venv-oidn
oidn_lib() { ls "$oidn_venv"/lib/python3*/site-packages/pyoidn/oidn/lib/libOpenImageDenoise.so.2 2>/dev/null | head -n 1; }
if [ -z "$(oidn_lib)" ]; then
  { rm -rf "$oidn_venv" && python3 -m venv "$oidn_venv" && "$oidn_venv/bin/python" -m pip install -q --no-deps pyoidn; } >/dev/null 2>&1 ||
    echo "warning: could not install pyoidn (Intel Open Image Denoise); the denoising tests are skipped" >&2
fi
if [ -n "$(oidn_lib)" ]; then
  NIEBLA_OIDN_LIBRARY="$PWD/$(oidn_lib)"
  export NIEBLA_OIDN_LIBRARY NIEBLA_REQUIRE_OIDN=1
fi

cargo test --workspace --all-targets
cargo test --workspace --doc

# The Python package (crates/niebla-py): an abi3 wheel built by maturin in a
# virtual environment of its own (.venv-py, reused by later runs), installed
# there and tested with pytest, against the release build of `niebla` for
# the tests that compare with the command line.
venv=.venv-py
if [ ! -x "$venv/bin/python" ]; then
  if ! python3 -m venv "$venv" >/dev/null 2>&1; then
    rm -rf "$venv"
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
      echo "installing python3-venv (the Python tests run in a virtual environment)"
      apt-get update -qq
      DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv >/dev/null
      python3 -m venv "$venv"
    else
      echo "error: python3 -m venv does not work here (install python3-venv)" >&2
      exit 1
    fi
  fi
fi
"$venv/bin/python" -m pip install -q "maturin>=1.5,<2" numpy pytest tqdm "dask[distributed]"
cargo build --release -p niebla-cli
rm -rf target/py-wheels
"$venv/bin/maturin" build --release -m crates/niebla-py/Cargo.toml -o target/py-wheels
"$venv/bin/python" -m pip install -q --force-reinstall --no-deps target/py-wheels/niebla-*.whl
status=0
NIEBLA_BIN="$PWD/target/release/niebla" "$venv/bin/python" -m pytest -q crates/niebla-py/tests || status=$?
# The live viewer in headless Chromium (Playwright from PyPI driving Debian's
# /usr/bin/chromium; the script prints why it skips when chromium is absent).
if [ "$status" = 0 ]; then
  "$venv/bin/python" -m pip install -q "playwright>=1.40,<2" pillow numpy
  viewer_status=0
  NIEBLA_BIN="$PWD/target/release/niebla" "$venv/bin/python" crates/niebla-view/tests/browser/test_viewer.py || viewer_status=$?
  if [ "$viewer_status" != 0 ] && [ "$viewer_status" != 77 ]; then
    echo "error: the browser test of niebla view failed (exit status $viewer_status)" >&2
    exit "$viewer_status"
  fi
fi
if [ "$status" = 5 ]; then
  echo "error: pytest collected no Python tests" >&2
  exit 1
elif [ "$status" != 0 ]; then
  echo "error: the Python tests failed (pytest exit status $status)" >&2
  exit "$status"
fi
