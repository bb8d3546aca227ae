#!/usr/bin/env bash
# Time the seed's Table 5.3 case (100 iterations) per scheme, precision and thread count;
# prints the wall time, the per-stage split, the fluid stage's rate (MLUPS of the sweep alone,
# and the bytes it moves: 72 per update in f32, 144 in f64, in place) and the coupling
# stage's passes from each summary.json. `fluid-only` is the same scene without [grains] and
# [coupling]. Compare the bytes with `cargo bench --bench memory_bandwidth` (its nine-plane
# in-place update is the kernel's roofline) taken in the same sitting.
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=target/release/grainflow
[ -x "$bin" ] || cargo build --release --quiet
out=${OUT:-runs/seed-table-5-3}
mkdir -p "$out"
cp jobs/seed-table-5-3/grains.csv "$out/grains.csv"
for scheme in ${SCHEMES:-psm bounce-back interpolated fluid-only}; do
  if [ "$scheme" = fluid-only ]; then
    python3 - jobs/seed-table-5-3/scene.toml "$out/scene-$scheme.toml" <<'PY'
import re, sys
keep, out = True, []
for line in open(sys.argv[1]):
    m = re.match(r"\s*\[([^\]]+)\]", line)
    if m:
        keep = m.group(1).split(".")[0] not in ("grains", "coupling")
    if keep:
        out.append(line)
open(sys.argv[2], "w").write("".join(out))
PY
  else
    sed "s/scheme = \"psm\"/scheme = \"$scheme\"/" jobs/seed-table-5-3/scene.toml > "$out/scene-$scheme.toml"
  fi
  for prec in ${PRECISIONS:-f32 f64}; do
    for t in ${THREADS:-1 2}; do
      d="$out/$scheme-$prec-t$t"
      "$bin" run "$out/scene-$scheme.toml" --out "$d" --precision "$prec" --threads "$t" --quiet >/dev/null || true
      python3 - "$d/summary.json" "$scheme" "$prec" "$t" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); st = s["stage_seconds"]
step = st["collide-stream"] + st["halo-wait"] + st["coupling"] + st["dem"] + st["boundaries"]
bytes_per_update = 72 if sys.argv[3] == "f32" else 144
print(f"{sys.argv[2]:13s} {sys.argv[3]} {sys.argv[4]} threads: 100 steps {step:6.2f} s "
      f"(fluid {st['collide-stream']:.2f}, coupling {st['coupling']:.2f} = {100*st['coupling']/step:.0f} %, "
      f"dem {st['dem']:.2f}, boundaries {st['boundaries']:.2f}); wall incl. output {s['wall_time_s']:.2f} s")
print(f"    fluid stage: {s['kernel_mlups']:.0f} MLUPS = "
      f"{s['kernel_mlups'] * bytes_per_update / 1e3:.1f} GB/s at {bytes_per_update} B per update")
passes = s.get("coupling_pass_seconds", {})
if passes:
    print("    coupling passes: " + ", ".join(f"{k} {v:.2f}" for k, v in passes.items()))
PY
    done
  done
done
