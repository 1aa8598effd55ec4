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

cargo test --workspace --all-targets
cargo test --workspace --doc
