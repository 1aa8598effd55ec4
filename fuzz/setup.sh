#!/usr/bin/env bash
# Installs what the fuzz targets need: a nightly toolchain (libFuzzer and the
# sanitizers need nightly rustc flags) and cargo-fuzz. The regression tests
# (crates/*/tests/fuzz_regressions.rs) run on stable and need none of this.
set -euo pipefail
rustup toolchain install nightly --profile minimal
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz
