#!/usr/bin/env python3
"""Draw the fluid's measured stability map (jobs/stability/lbm-map.csv, from
`grainflow stability-map`): one panel per operator, tau - 1/2 (log) against the lattice Mach
number, each point marked by which of the two test flows stayed stable, and the limits
`grainflow check` uses for each flow (between the largest tau that failed and the smallest from
which every larger one was stable: their geometric mean in tau - 1/2).

Usage: scripts/plot-stability.py [MAP_CSV] [OUT_PNG]
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

path = sys.argv[1] if len(sys.argv) > 1 else "jobs/stability/lbm-map.csv"
out = sys.argv[2] if len(sys.argv) > 2 else "jobs/stability/stability.png"
rows = list(csv.DictReader(open(path)))
ops = ["bgk", "bgk+smag", "trt", "trt+smag", "mrt", "mrt+smag"]
fig, axes = plt.subplots(2, 3, figsize=(13, 7.5), sharex=True, sharey=True)
style = {
    (True, True): ("o", "tab:green", "stable in both flows"),
    (True, False): ("s", "tab:orange", "cavity blew up"),
    (False, True): ("D", "tab:blue", "shear layer blew up"),
    (False, False): ("x", "tab:red", "both blew up"),
}
for ax, op in zip(axes.flat, ops):
    pts = {}
    for r in rows:
        if r["operator"] != op:
            continue
        key = (float(r["tau"]), float(r["mach"]))
        pts.setdefault(key, {})[r["flow"]] = r["stable"] == "1"
    seen = set()
    for (tau, mach), flows in pts.items():
        k = (flows.get("shear-layer", False), flows.get("cavity", False))
        m, c, label = style[k]
        ax.scatter(tau - 0.5, mach, marker=m, c=c, s=28, label=None if k in seen else label)
        seen.add(k)
    # check's limit per flow and Mach: the geometric mean, in tau - 1/2, of the largest tau
    # that failed and the smallest from which every larger one was stable.
    machs = sorted({m for _, m in pts})
    for flow, colour in (("shear-layer", "tab:blue"), ("cavity", "tab:orange")):
        lim = []
        for mach in machs:
            taus = sorted(t for t, m in pts if m == mach)
            # From the largest stable tau down (failures above it cap the band instead).
            stable = [t for t in taus if pts[(t, mach)].get(flow)]
            taus = [t for t in taus if stable and t <= stable[-1]]
            limit, failed = None, None
            for t in reversed(taus):
                if not pts[(t, mach)].get(flow):
                    failed = t
                    break
                limit = t
            if limit is None:
                continue
            x = limit - 0.5 if failed is None else ((failed - 0.5) * (limit - 0.5)) ** 0.5
            lim.append((x, mach))
        if lim:
            ax.plot([p[0] for p in lim], [p[1] for p in lim], c=colour, lw=1.2,
                    label=f"check's limit, {flow}")
    ax.set_xscale("log")
    ax.set_title(op)
    ax.grid(alpha=0.3)
for ax in axes[-1]:
    ax.set_xlabel("τ − ½")
for ax in axes[:, 0]:
    ax.set_ylabel("lattice Mach number U / c_s")
axes[0, 0].legend(fontsize=8, loc="upper left")
fig.suptitle("Measured stability: double shear layer and lid-driven cavity, 64², 10 000 steps; stable: finite and below 1.5 × the driving speed")
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}")
