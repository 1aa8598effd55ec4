#!/usr/bin/env bash
# Checks that a change of structure leaves every image bit-identical: renders
# the same cases with the `niebla` of commit BASE (built in a worktree under
# target/identical) and with the working tree's, and compares the EXR pixels
# bit for bit (header attributes are ignored).
#   bash scripts/images_identical.sh BASE [SPP]
# Cases: every integrator on the built-in default scene and on
# scenes/smoke.json, each scene of scenes/ with its own integrator, and each
# Mitsuba XML scene of scenes/mitsuba/ that BASE has too.
# BASE_BIN=path uses that binary (built from BASE) instead of building one.
set -euo pipefail
cd "$(dirname "$0")/.."
base=${1:?usage: images_identical.sh BASE [SPP]}
spp=${2:-2}
root=$PWD/target/identical
mkdir -p "$root"
rev=$(git rev-parse --short "$base")
src=$root/src-$rev
if [ -n "${BASE_BIN:-}" ]; then
  cp "$BASE_BIN" "$root/niebla-$rev"
elif [ ! -x "$root/niebla-$rev" ]; then
  rm -rf "$src"
  git worktree prune
  git worktree add --detach "$src" "$rev" >/dev/null
  (cd "$src" && cargo build --release -q -p niebla-cli --target-dir "$root/target-base")
  cp "$root/target-base/release/niebla" "$root/niebla-$rev"
  git worktree remove --force "$src"
fi
cargo build --release -q -p niebla-cli
cargo build --release -q -p niebla --example exr_identical
head_bin=$PWD/target/release/niebla
cmp_bin=$PWD/target/release/examples/exr_identical
export NIEBLA_CACHE_DIR=
cases=()
for scene in default scenes/smoke.json; do
  for integrator in emission single single:march single:equiangular single:mis volpath analytic hegeman zhou photon ppm; do
    cases+=("$scene $integrator")
  done
done
for scene in scenes/*.json; do
  cases+=("$scene own")
done
for scene in scenes/mitsuba/*.xml; do
  if git cat-file -e "$rev:$scene" 2>/dev/null; then
    cases+=("$scene own")
  fi
done
out=$root/images
rm -rf "$out" && mkdir -p "$out/base" "$out/head"
failed=0
for case in "${cases[@]}"; do
  read -r scene integrator <<<"$case"
  args=(render --quiet --spp "$spp")
  [ "$scene" != default ] && args+=("$scene")
  if [ "$integrator" != own ]; then
    args+=(--integrator "${integrator%%:*}")
    [[ $integrator == *:* ]] && args+=(--sampling "${integrator#*:}")
  fi
  name=$(basename "${scene%.*}")-${integrator/:/-}.exr
  "$root/niebla-$rev" "${args[@]}" -o "$out/base/$name" >/dev/null
  "$head_bin" "${args[@]}" -o "$out/head/$name" >/dev/null
  "$cmp_bin" "$out/base/$name" "$out/head/$name" || { failed=$((failed + 1)); echo "differs: $case"; }
done
echo "${#cases[@]} images compared with $rev at $spp spp: $failed differ"
[ "$failed" = 0 ]
