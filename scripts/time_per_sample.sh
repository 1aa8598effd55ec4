#!/usr/bin/env bash
# Time per sample of two `niebla` binaries on the Mitsuba comparison scenes
# (bench/scenes, their own integrator, volpath): the render time that
# `niebla render` prints, best of RUNS runs, at SPP samples per pixel.
#   bash scripts/time_per_sample.sh BASE_BIN HEAD_BIN [SPP] [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
base=${1:?usage: time_per_sample.sh BASE_BIN HEAD_BIN [SPP] [RUNS]}
head=${2:?usage: time_per_sample.sh BASE_BIN HEAD_BIN [SPP] [RUNS]}
spp=${3:-16}
runs=${4:-3}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
best() {
  local bin=$1 scene=$2 t best=""
  for _ in $(seq "$runs"); do
    t=$("$bin" render "$scene" --spp "$spp" --quiet -o "$out/x.exr" | sed -n 's/.* in \([0-9.]*\) s .*/\1/p')
    if [ -z "$best" ] || awk "BEGIN{exit !($t < $best)}"; then best=$t; fi
  done
  echo "$best"
}
printf "%-14s %10s %10s %8s   (seconds at %s spp, best of %s)\n" scene base head head/base "$spp" "$runs"
for scene in bench/scenes/*.json; do
  a=$(best "$base" "$scene")
  b=$(best "$head" "$scene")
  printf "%-14s %10s %10s %8.3f\n" "$(basename "$scene" .json)" "$a" "$b" "$(awk "BEGIN{print $b / $a}")"
done
