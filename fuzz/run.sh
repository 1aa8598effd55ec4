#!/usr/bin/env bash
# Runs one fuzz target for a fixed time (default 600 s) or 1,000,000
# executions, whichever comes first, with the limits that turn OOMs and hangs
# into findings. Crashes land in fuzz/artifacts/<target>/; the log in
# fuzz/logs/<target>.log ends with libFuzzer's execution count.
#
# Usage: fuzz/run.sh scene|render|vdb|vol|npy|ply|obj [SECONDS]
# Run the targets one at a time (each uses a core and up to 2 GiB).
set -euo pipefail
cd "$(dirname "$0")"
target=$1
seconds=${2:-600}
mkdir -p logs "corpus/$target" "artifacts/$target"
# The render target runs with debug assertions (its per-sample finiteness checks).
flags=()
[ "$target" = render ] && flags=(--debug-assertions)
cargo +nightly fuzz run "${flags[@]}" "$target" "corpus/$target" -- \
    -max_total_time="$seconds" -runs=1000000 -rss_limit_mb=2048 -timeout=10 \
    -max_len=262144 -print_final_stats=1 \
    -artifact_prefix="artifacts/$target/" $([ -f "$target.dict" ] && echo "-dict=$target.dict") 2>&1 | tee "logs/$target.log"
