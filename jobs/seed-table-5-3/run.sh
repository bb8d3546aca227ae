#!/usr/bin/env bash
# Time the seed's Table 5.3 case (100 iterations) per scheme, precision and thread count;
# prints the wall time, the per-stage split and the coupling stage's passes from each
# summary.json.
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=target/release/grainflow
[ -x "$bin" ] || cargo build --release --quiet
out=${OUT:-runs/seed-table-5-3}
for scheme in ${SCHEMES:-psm bounce-back interpolated}; do
  for prec in ${PRECISIONS:-f32 f64}; do
    for t in ${THREADS:-1 2}; do
      d="$out/$scheme-$prec-t$t"
      mkdir -p "$out"
      cp jobs/seed-table-5-3/grains.csv "$out/grains.csv"
      sed "s/scheme = \"psm\"/scheme = \"$scheme\"/" jobs/seed-table-5-3/scene.toml > "$out/scene-$scheme.toml"
      "$bin" run "$out/scene-$scheme.toml" --out "$d" --precision "$prec" --threads "$t" --quiet >/dev/null || true
      python3 - "$d/summary.json" "$scheme" "$prec" "$t" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); st = s["stage_seconds"]
step = st["collide-stream"] + st["halo-wait"] + st["coupling"] + st["dem"] + st["boundaries"]
print(f"{sys.argv[2]:13s} {sys.argv[3]} {sys.argv[4]} threads: 100 steps {step:6.2f} s "
      f"(fluid {st['collide-stream']:.2f}, coupling {st['coupling']:.2f} = {100*st['coupling']/step:.0f} %, "
      f"dem {st['dem']:.2f}, boundaries {st['boundaries']:.2f}); wall incl. output {s['wall_time_s']:.2f} s")
passes = s.get("coupling_pass_seconds", {})
if passes:
    print("    coupling passes: " + ", ".join(f"{k} {v:.2f}" for k, v in passes.items()))
PY
    done
  done
done
