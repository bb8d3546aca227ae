#!/usr/bin/env bash
# The full column-collapse sweep (a = 0.5, 1, 2, 4, 8) and the run-out plot.
# Usage: jobs/column-collapse/run.sh [ranks]   (about 5 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/../.."
ranks=${1:-1}
cargo build --release --quiet
for a in 0.5 1 2 4 8; do
  if [ "$ranks" -gt 1 ]; then
    mpirun --oversubscribe --bind-to none -np "$ranks" target/release/grainflow run \
      "jobs/column-collapse/a$a.toml" --out "runs/column-collapse/a$a" --quiet --threads 1
  else
    target/release/grainflow run "jobs/column-collapse/a$a.toml" --out "runs/column-collapse/a$a" --quiet
  fi
done
python3 scripts/plot-collapse.py runs/column-collapse --out runs/column-collapse/runout.png
