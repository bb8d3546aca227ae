#!/usr/bin/env bash
# Run every submerged column collapse and its dry twin (about 25 minutes on 2 cores), then
# print the comparison table: `jobs/submerged-collapse/run.sh [OUT]` (default runs/submerged).
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=target/release/grainflow
[ -x "$bin" ] || cargo build --release --quiet
out=${1:-runs/submerged}
mkdir -p "$out"
for a in a0.5 a1 a2; do
  for p in loose dense; do
    for kind in dry sub; do
      name="$kind-$a-$p"
      [ -f "$out/$name/summary.json" ] && continue
      "$bin" run "jobs/submerged-collapse/$name.toml" --out "$out/$name" --quiet >"$out/$name.log" 2>&1 || true
    done
  done
done
python3 scripts/submerged-table.py "$out"
