#!/usr/bin/env bash
# Compare two grainflow binaries on the seed's Table 5.3 case by interleaved runs (this
# kind of shared machine drifts by ±30 % within minutes, so only runs taken side by side
# compare): for each scheme, N rounds of A then B, each printing the step time (the final
# snapshot excluded), the fluid and coupling stages, the coupling's share and its passes.
# At the end it prints, per scheme and binary, the median and range of the step, the fluid
# stage, the coupling stage and its share, and of each coupling pass (runs kept in
# $OUT/pairs.tsv).
# Usage: jobs/seed-table-5-3/pairs.sh BIN_A BIN_B [N]   (SCHEMES, THREADS, PRECISION, OUT)
set -euo pipefail
cd "$(dirname "$0")/../.."
a=$(realpath "$1"); b=$(realpath "$2"); n=${3:-3}
out=${OUT:-runs/seed-table-5-3-pairs}
mkdir -p "$out"
cp jobs/seed-table-5-3/grains.csv "$out/grains.csv"
: > "$out/pairs.tsv"
for scheme in ${SCHEMES:-psm bounce-back interpolated}; do
  sed "s/scheme = \"psm\"/scheme = \"$scheme\"/" jobs/seed-table-5-3/scene.toml > "$out/scene-$scheme.toml"
  for round in $(seq "$n"); do
    for label in A B; do
      bin=$a; [ "$label" = B ] && bin=$b
      d="$out/run-$scheme"
      rm -rf "$d"
      "$bin" run "$out/scene-$scheme.toml" --out "$d" --precision "${PRECISION:-f32}" \
        --threads "${THREADS:-2}" --quiet >/dev/null 2>&1 || true
      python3 - "$d/summary.json" "$scheme" "$round" "$bin" "$label" "$out/pairs.tsv" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); st = s["stage_seconds"]
step = sum(v for k, v in st.items() if k not in ("output", "checkpoint"))
passes = " ".join(f"{k} {v:.3f}" for k, v in s.get("coupling_pass_seconds", {}).items())
print(f"{sys.argv[2]:12s} round {sys.argv[3]} {sys.argv[4]}: step {step:.2f} s, fluid "
      f"{st['collide-stream']:.2f}, coupling {st['coupling']:.2f} "
      f"({100 * st['coupling'] / step:.1f} %); {passes}")
row = {"step": step, "fluid": st["collide-stream"], "coupling": st["coupling"],
       "share %": 100 * st["coupling"] / step, **s.get("coupling_pass_seconds", {})}
with open(sys.argv[6], "a") as f:
    f.write("\t".join([sys.argv[2], sys.argv[5]] + [f"{k}={v:.6f}" for k, v in row.items()]) + "\n")
PY
    done
  done
done
# The summary: median [min–max] of every quantity over each binary's rounds.
python3 - "$out/pairs.tsv" "$a" "$b" <<'PY'
import statistics, sys
runs = {}
for line in open(sys.argv[1]):
    scheme, label, *kv = line.rstrip("\n").split("\t")
    runs.setdefault((scheme, label), []).append({k: float(v) for k, v in (x.split("=") for x in kv)})
print(f"\nmedian [min–max] per binary (A = {sys.argv[2]}, B = {sys.argv[3]}):")
for (scheme, label), rows in runs.items():
    keys = [k for k in rows[0] if any(r[k] > 0 for r in rows)]
    cells = []
    for k in keys:
        v = [r[k] for r in rows]
        cells.append(f"{k} {statistics.median(v):.3f} [{min(v):.3f}–{max(v):.3f}]")
    print(f"{scheme:12s} {label} ({len(rows)} runs): " + ", ".join(cells))
PY
