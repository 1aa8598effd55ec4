#!/usr/bin/env bash
# Relative MSE (niebla::film::Image::relative_mse) of the independent,
# sequential Sobol and laid-out Sobol samplers at 16, 64 and 256 spp on bench/scenes and the default scene,
# at 1/DIV of their resolution, against a reference of REF spp (Sobol, seed
# 1000, independent of the seeds measured); the mean over SEEDS seeds.
#   bash scripts/sampler_error.sh BIN [REF] [SEEDS] [DIV] [SCENES...]
# Needs the example: cargo build --release -p niebla --example relative_mse
# and the bench volumes (python bench/volumes.py).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "${1:?usage: sampler_error.sh BIN [REF] [SEEDS] [DIV] [SCENES...]}")
ref=${2:-4096}
seeds=${3:-2}
div=${4:-4}
shift $(( $# < 4 ? $# : 4 ))
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(bench/scenes/*.json scenes/default.json)
mse=target/release/examples/relative_mse
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
printf "%-12s %-11s %12s %12s %12s   (relative MSE, mean of %s seeds; reference %s spp; M samples/s at 256 spp)\n" \
  scene sampler 16 64 256 "$seeds" "$ref"
for scene in "${scenes[@]}"; do
  name=$(basename "$scene" .json)
  small="$out/$name.json"
  python3 - "$scene" "$small" "$div" <<'PY'
import json, os, sys
src, dst, div = sys.argv[1], sys.argv[2], int(sys.argv[3])
d = json.load(open(src))
cam = d["camera"]
cam["width"], cam["height"] = max(1, cam["width"] // div), max(1, cam["height"] // div)
base = os.path.dirname(os.path.abspath(src))
def absolute(o):
    if isinstance(o, dict):
        for k, v in o.items():
            if k == "file" and isinstance(v, str):
                o[k] = os.path.join(base, v)
            else:
                absolute(v)
    elif isinstance(o, list):
        for v in o:
            absolute(v)
absolute(d)
json.dump(d, open(dst, "w"))
PY
  "$bin" render "$small" --spp "$ref" --seed 1000 --sampler sobol --quiet -o "$out/ref.exr" > /dev/null
  for sampler in independent sobol_sequential sobol; do
    row=()
    for spp in 16 64 256; do
      sum=0
      for seed in $(seq 1 "$seeds"); do
        line=$("$bin" render "$small" --spp "$spp" --seed "$seed" --sampler "$sampler" --quiet -o "$out/x.exr")
        speed=$(echo "$line" | sed -n 's/.*(\([0-9.]*\) M samples\/s).*/\1/p')
        e=$("$mse" "$out/ref.exr" "$out/x.exr" | cut -d' ' -f1)
        sum=$(awk "BEGIN{print $sum + $e}")
      done
      row+=("$(awk "BEGIN{printf \"%.3e\", $sum / $seeds}")")
    done
    printf "%-12s %-11s %12s %12s %12s   %s\n" "$name" "$sampler" "${row[@]}" "$speed"
  done
done
