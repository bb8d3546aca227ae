#!/usr/bin/env bash
# Compare two grainflow binaries on the seed's Table 5.3 case by interleaved runs (this
# kind of shared machine drifts by ±30 % within minutes, so only runs taken side by side
# compare): for each scheme, N rounds of A then B, each printing the step time (the final
# snapshot excluded), the fluid and coupling stages, the coupling's share and its passes.
# Usage: jobs/seed-table-5-3/pairs.sh BIN_A BIN_B [N]   (SCHEMES, THREADS, PRECISION, OUT)
set -euo pipefail
cd "$(dirname "$0")/../.."
a=$(realpath "$1"); b=$(realpath "$2"); n=${3:-3}
out=${OUT:-runs/seed-table-5-3-pairs}
mkdir -p "$out"
cp jobs/seed-table-5-3/grains.csv "$out/grains.csv"
for scheme in ${SCHEMES:-psm bounce-back interpolated}; do
  sed "s/scheme = \"psm\"/scheme = \"$scheme\"/" jobs/seed-table-5-3/scene.toml > "$out/scene-$scheme.toml"
  for round in $(seq "$n"); do
    for bin in "$a" "$b"; do
      d="$out/run-$scheme"
      rm -rf "$d"
      "$bin" run "$out/scene-$scheme.toml" --out "$d" --precision "${PRECISION:-f32}" \
        --threads "${THREADS:-2}" --quiet >/dev/null 2>&1 || true
      python3 - "$d/summary.json" "$scheme" "$round" "$bin" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); st = s["stage_seconds"]
step = sum(v for k, v in st.items() if k not in ("output", "checkpoint"))
passes = " ".join(f"{k} {v:.3f}" for k, v in s.get("coupling_pass_seconds", {}).items())
print(f"{sys.argv[2]:12s} round {sys.argv[3]} {sys.argv[4]}: step {step:.2f} s, fluid "
      f"{st['collide-stream']:.2f}, coupling {st['coupling']:.2f} "
      f"({100 * st['coupling'] / step:.1f} %); {passes}")
PY
    done
  done
done
