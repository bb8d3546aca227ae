#!/usr/bin/env bash
# The canonical MPM column collapses (a = 0.5 ... 4 at 2 mm cells with 4x4 points, a = 8 at
# 4 mm, FLIP + 5 % PIC, rough floor), the earlier sweep (4 mm, Coulomb floor) and the
# studies: rough base, 2 mm cells, shape functions, points per cell, pure FLIP, APIC, mu(I)
# friction, side walls, rough floor, the published resolution; then the table and the plot with the DEM sweep and the published laws.
# Usage: [THREADS=n] jobs/mpm-collapse/run.sh [ranks] [scene names...]   (all scenes: about
# three and a half hours on 2 cores; e.g. `run.sh 1 a0.5 a1 a2` for the short columns)
set -euo pipefail
cd "$(dirname "$0")/../.."
ranks=${1:-1}
shift || true
cargo build --release --quiet
out=runs/mpm-collapse
mkdir -p "$out"
# The study variants are written into the run folder, not committed.
python3 jobs/mpm-collapse/make-scenes.py "$out/scenes" >/dev/null
names=("$@")
if [ ${#names[@]} -eq 0 ]; then
  names=(a0.5 a1 a2 a4 a8 a0.5-h4mm a1-h4mm a2-h4mm a4-h4mm a8-h4mm a0.5-rough a1-rough a2-rough a4-rough
         a0.5-h2mm a1-h2mm a2-h2mm a0.5-h2mm-rough a1-h2mm-rough a2-h2mm-rough a2-linear a2-h2mm-linear a2-ppc4 a2-flip
         a4-h2mm a4-linear a4-h2mm-linear a4-ppc4 a4-flip
         a0.5-apic a1-apic a2-apic a4-apic a8-apic a0.5-h2mm-apic a1-h2mm-apic a2-h2mm-apic
         a0.5-mui a1-mui a2-mui a4-mui a8-mui a0.5-h2mm-mui a1-h2mm-mui a2-h2mm-mui a4-h2mm-mui
         a0.5-apic-mui a1-apic-mui a2-apic-mui a4-apic-mui a8-apic-mui
         a0.5-apic-w5 a1-apic-w5 a2-apic-w5 a0.5-apic-w10 a1-apic-w10 a2-apic-w10 a4-apic-w10
         a8-apic-w10 a0.5-apic-w20 a1-apic-w20 a2-apic-w20
         a0.5-apic-mui-w5 a1-apic-mui-w5 a2-apic-mui-w5 a0.5-apic-mui-w10 a1-apic-mui-w10
         a2-apic-mui-w10 a4-apic-mui-w10 a8-apic-mui-w10 a0.5-apic-mui-w20 a1-apic-mui-w20
         a2-apic-mui-w20 a0.5-h2mm-apic-mui-w10 a1-h2mm-apic-mui-w10 a2-h2mm-apic-mui-w10
         a0.5-apic-mui-w10-phi23.8 a1-apic-mui-w10-phi23.8 a2-apic-mui-w10-phi23.8
         a0.5-apic-mui-w10-rough a1-apic-mui-w10-rough a2-apic-mui-w10-rough a4-apic-mui-w10-rough
         a8-apic-mui-w10-rough a0.5-h2mm-apic-mui-w10-rough a1-h2mm-apic-mui-w10-rough
         a2-h2mm-apic-mui-w10-rough a0.5-h2mm-ppc4-apic-mui-w10-rough a1-h2mm-ppc4-apic-mui-w10-rough
         a2-h2mm-ppc4-apic-mui-w10-rough)
fi
for name in "${names[@]}"; do
  scene=$out/scenes/$name.toml
  if [ "$ranks" -gt 1 ]; then
    mpirun --oversubscribe --bind-to none -np "$ranks" target/release/grainflow run \
      "$scene" --out "$out/$name" --quiet --threads 1 || true
  else
    target/release/grainflow run "$scene" --out "$out/$name" --quiet --threads "${THREADS:-2}" || true
  fi
done
python3 scripts/plot-mpm-collapse.py "$out" --out jobs/mpm-collapse/runout.png
