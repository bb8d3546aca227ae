#!/usr/bin/env python3
"""Draw the fluid's measured stability map (jobs/stability/lbm-map.csv, from
`grainflow stability-map`): one panel per operator, tau - 1/2 (log) against the lattice Mach
number, each point marked by which of the two test flows stayed stable, and the limit
`grainflow check` uses (the smallest tau from which every larger one was stable in both flows).

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
    # The limit: per Mach, the smallest tau from which every larger tau was stable in both.
    machs = sorted({m for _, m in pts})
    lim = []
    for mach in machs:
        taus = sorted(t for t, m in pts if m == mach)
        limit = None
        for t in reversed(taus):
            f = pts[(t, mach)]
            if not (f.get("shear-layer") and f.get("cavity")):
                break
            limit = t
        if limit is not None:
            lim.append((limit - 0.5, mach))
    if lim:
        ax.step([p[0] for p in lim], [p[1] for p in lim], where="mid", c="k", lw=1, label="check's limit")
    ax.set_xscale("log")
    ax.set_title(op)
    ax.grid(alpha=0.3)
for ax in axes[-1]:
    ax.set_xlabel("τ − ½")
for ax in axes[:, 0]:
    ax.set_ylabel("lattice Mach number U / c_s")
axes[0, 0].legend(fontsize=8, loc="upper left")
fig.suptitle("Measured stability: double shear layer and lid-driven cavity, 64², 4000 steps (grainflow stability-map)")
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}")
