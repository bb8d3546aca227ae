#!/usr/bin/env bash
# Set up, build in release mode and run the default scene: the Karman vortex street at Re 112.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo build --release --quiet
out=runs/karman-re112
./target/release/grainflow run jobs/karman/re112.toml --out "$out"
echo
echo "Output:   $out/summary.json, $out/fields.h5 (+ fields.xdmf for ParaView), $out/probe_*.csv"
echo "Pictures: $out/pictures/ (speed_*.png, vorticity_*.png)"
