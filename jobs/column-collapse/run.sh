#!/usr/bin/env bash
# The full column-collapse sweep: a = 0.5, 1, 2, 3, 4, 6, 8, 16, each from three packings (seeds 1-3;
# seed 1 is the committed a*.toml), then the table, fits and plot.
# Usage: jobs/column-collapse/run.sh [ranks]   (about 30 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/../.."
ranks=${1:-1}
cargo build --release --quiet
out=runs/column-collapse
mkdir -p "$out/scenes"
for seed in 2 3; do
  python3 jobs/column-collapse/make-scenes.py --out "$out/scenes" --seed "$seed" >/dev/null
done
for a in 0.5 1 2 3 4 6 8 16; do
  for seed in 1 2 3; do
    if [ "$seed" = 1 ]; then scene=jobs/column-collapse/a$a.toml; name=a$a
    else scene=$out/scenes/a$a-s$seed.toml; name=a$a-s$seed; fi
    if [ "$ranks" -gt 1 ]; then
      mpirun --oversubscribe --bind-to none -np "$ranks" target/release/grainflow run \
        "$scene" --out "$out/$name" --quiet --threads 1 || true
    else
      target/release/grainflow run "$scene" --out "$out/$name" --quiet || true
    fi
  done
done
python3 scripts/plot-collapse.py "$out" --out "$out/runout.png"
