#!/usr/bin/env bash
# Run the validation scenes to steady state on the GPU backend and on the CPU, and print
# the checks of both. On Mesa lavapipe (no GPU) this takes about 15 minutes; on a real GPU
# seconds. Usage: jobs/gpu/validate.sh [f32|f64] [OUT]
set -euo pipefail
cd "$(dirname "$0")/../.."
precision="${1:-f64}"
out="${2:-runs/gpu-validate}"
cargo build --release --quiet
export NODEVICE_SELECT=1
for scene in jobs/poiseuille/scene.toml jobs/cavity/re100.toml jobs/cylinder/scene.toml; do
  name="$(basename "$(dirname "$scene")")"
  for backend in cpu gpu; do
    dir="$out/$name-$backend-$precision"
    set +e
    ./target/release/grainflow run "$scene" --backend "$backend" --precision "$precision" \
      --out "$dir" --quiet > "$dir.log" 2>&1
    code=$?
    set -e
    echo "== $scene on $backend ($precision): exit $code"
    grep -E "check|steps in" "$dir.log" || true
  done
done
