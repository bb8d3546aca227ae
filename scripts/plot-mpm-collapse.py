#!/usr/bin/env python3
"""Run-out of the MPM column-collapse sweep against the experiments, the published DEM law
and grainflow's own DEM sweep.

Reads runs/mpm-collapse/<name>/summary.json (jobs/mpm-collapse/run.sh): the main sweep is
a<a>-h4mm (4 mm cells, GIMP, 2x2 points per cell, Coulomb floor); the canonical scenes a<a>
(2 mm cells, 4x4 points, FLIP + 5 % PIC, rough floor: the published resolution; a = 8 at
4 mm); the study runs are a<a>-h2mm, -linear, -ppc4,
-flip, -rough, -mui (mu(I) friction), -apic (APIC transfer), -apic-mui, and -apic-w<W> /
-apic-mui-w<W> (side walls of a quasi-2-D channel W cm apart), -apic-mui-w10-rough (and a rough floor).
Prints a table of (L_f - L_i)/L_i and H_f/L_i against the experiments' law (Lajeunesse et
al. 2005) and the 2-D DEM law, the study's differences, and draws run-out vs a on log axes
with the DEM sweep of issue 5 (its committed table, jobs/column-collapse/README.md).
"""
import argparse
import glob
import json
import math
import os

EXP = (1.2, 1.9, 2.3)   # Lajeunesse et al. 2005: 1.2 a below a ~ 2.3, 1.9 a^(2/3) above
DEM = (1.67, 2.7, 2.7)  # published 2-D DEM of disks: 1.67 a below a ~ 2.7, 2.7 a^(2/3) above
# grainflow's DEM sweep (jobs/column-collapse/README.md): a, mean run-out, std over packings.
DEM_SWEEP = [(0.5, 0.742, 0.018), (1.0, 1.540, 0.137), (2.0, 3.284, 0.079), (2.99, 4.754, 0.304),
             (4.0, 6.606, 0.170), (5.92, 9.409, 0.186), (7.88, 11.71, 0.49), (15.66, 19.67, 0.50)]


def law(a, c):
    lin, pow_, t = c
    return lin * a if a < t else pow_ * a ** (2 / 3)


def thick_front(run_dir, min_height, li):
    """Run-out to the farthest cell column, contiguous from the wall, whose highest point
    centre in the last snapshot of mpm.h5 is at least min_height (m) above the floor."""
    import h5py
    import numpy as np
    s = json.load(open(os.path.join(run_dir, "summary.json")))
    h = cell_size(s)
    with h5py.File(os.path.join(run_dir, "mpm.h5"), "r") as f:
        last = sorted(k for k in f if k.startswith("step_"))[-1]
        pos = f[last]["position"][:, :2]
    cols = (pos[:, 0] / h).astype(int)
    top = np.zeros(cols.max() + 2)
    np.maximum.at(top, cols, pos[:, 1])
    i = 0
    while i < len(top) and top[i] >= min_height:
        i += 1
    return (i * h - li) / li


def cell_size(s):
    """The run's cell size (m): the summary's own figure, else its scene's ([domain] spacing_m,
    or [mpm] cell_size_m in runs of the older scene dialect)."""
    if "cell_size_m" in s:
        return s["cell_size_m"]
    scene = s.get("scene", {})
    if "spacing_m" in scene.get("domain", {}):
        return scene["domain"]["spacing_m"]
    return scene["mpm"]["cell_size_m"]


def load(folder):
    runs = {}
    for f in sorted(glob.glob(os.path.join(folder, "*", "summary.json"))):
        s = json.load(open(f))
        if s.get("status") not in ("ok", "checks-failed") or "collapse.runout" not in s["results"]:
            print(f"skipped {f}: status {s.get('status')}, {s.get('error')}")
            continue
        runs[os.path.basename(os.path.dirname(f))] = s
    return runs


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("runs", help="folder with one run folder per scene")
    p.add_argument("--out", default=None, help="PNG to write")
    p.add_argument("--front-min-height", type=float, default=None, metavar="M",
                   help="print the run-out to where the deposit's top point centre drops "
                        "below M metres, recomputed from mpm.h5 (needs h5py); without it the "
                        "run's own collapse.thick_runout is printed where the scene asked for one")
    args = p.parse_args()
    runs = load(args.runs)
    main_rows, rough_rows, mui_rows, apic_rows, apic_mui_rows = [], [], [], [], []
    walls_rows, walls_mui_rows, walls_mui_rough_rows, published_rows = [], [], [], []
    print(f"{'scene':>17} {'a':>5} {'points':>7} {'runout':>7} {'exp.':>6} {'dev':>7} {'DEM law':>7} {'dev':>7} {'H_f/L_i':>7} {'t/tau_c':>7} {'Mpts/s':>6}")
    for name, s in sorted(runs.items(), key=lambda kv: (kv[1]["results"]["collapse.aspect_ratio"], kv[0])):
        r = s["results"]
        a, ro = r["collapse.aspect_ratio"], r["collapse.runout"]
        e, d = law(a, EXP), law(a, DEM)
        thick = ""
        if "collapse.thick_runout" in r and not args.front_min_height:
            t = r["collapse.thick_runout"]
            thick = f"  thick front {t:.3f} ({100*(t/e-1):+.0f}% vs exp.)"
        elif args.front_min_height:
            t = thick_front(os.path.join(args.runs, name), args.front_min_height,
                            r["collapse.initial_length_m"])
            thick = f"  thick front {t:.3f} ({100*(t/e-1):+.0f}% vs exp.)"
        print(f"{name:>17} {a:5.2f} {s['points']:7d} {ro:7.3f} {e:6.3f} {100*(ro/e-1):+6.1f}% {d:7.3f} {100*(ro/d-1):+6.1f}% "
              f"{r['collapse.final_height']:7.3f} {r['collapse.stop_time']:7.2f} {s['point_steps_per_s']/1e6:6.2f}{thick}")
        if "-" not in name:
            published_rows.append((a, ro))
        elif name.endswith("-h4mm"):
            main_rows.append((a, ro))
        elif name.endswith("-apic-mui-w10-rough") and "h2mm" not in name:
            walls_mui_rough_rows.append((a, ro))
        elif name.endswith("-rough") and "-w" not in name and "h2mm" not in name:
            rough_rows.append((a, ro))
        elif name.endswith("-apic-w10") and "h2mm" not in name:
            walls_rows.append((a, ro))
        elif name.endswith("-apic-mui-w10") and "h2mm" not in name:
            walls_mui_rows.append((a, ro))
        elif "-w" in name:
            pass
        elif name.endswith("-apic-mui"):
            apic_mui_rows.append((a, ro))
        elif name.endswith("-apic") and "h2mm" not in name:
            apic_rows.append((a, ro))
        elif name.endswith("-mui") and "h2mm" not in name:
            mui_rows.append((a, ro))
    for a in (2, 4):
        base = runs.get(f"a{a}-h4mm")
        if not base:
            continue
        b = base["results"]["collapse.runout"]
        for var in ("h2mm", "linear", "h2mm-linear", "ppc4", "flip", "rough", "mui", "apic",
                    "h2mm-apic", "apic-mui", "apic-w10", "apic-mui-w10", "apic-mui-w10-rough"):
            v = runs.get(f"a{a}-{var}")
            if v:
                print(f"a = {a}: {var:6s} run-out {v['results']['collapse.runout']:.3f} vs {b:.3f} ({100*(v['results']['collapse.runout']/b-1):+.1f} %)")
    if not args.out or not main_rows:
        return
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not installed: table only")
        return
    fig, ax = plt.subplots(figsize=(9.5, 4.5))
    xs = [0.4 * 1.05 ** i for i in range(82)]
    ax.loglog(xs, [law(a, EXP) for a in xs], "k-", label="experiments (Lajeunesse et al. 2005)")
    ax.loglog(xs, [law(a, DEM) for a in xs], "k--", label="published 2-D DEM law")
    dem = DEM_SWEEP
    ax.errorbar([d[0] for d in dem], [d[1] for d in dem], yerr=[d[2] for d in dem], fmt="s",
                color="tab:blue", label="grainflow DEM (disks)")
    series = [
        (main_rows, "o", "tab:red", "Coulomb base (tan 24.8 deg), FLIP + 5% PIC"),
        (rough_rows, "^", "tab:orange", "rough (no-slip) base, FLIP + 5% PIC"),
        (mui_rows, "v", "tab:green", "Coulomb base, mu(I) friction"),
        (apic_rows, "D", "tab:purple", "Coulomb base, APIC (no PIC damping)"),
        (apic_mui_rows, "d", "tab:brown", "APIC + mu(I)"),
        (walls_rows, "P", "tab:gray", "APIC, side walls 10 cm apart"),
        (walls_mui_rows, "X", "black", "APIC + mu(I), side walls 10 cm apart"),
        (walls_mui_rough_rows, "*", "tab:cyan", "APIC + mu(I), side walls 10 cm, rough floor"),
        (published_rows, "h", "tab:olive", "2 mm, 4x4 points, FLIP + 5% PIC, rough floor"),
    ]
    for rows, marker, color, label in series:
        if rows:
            ax.loglog([a for a, _ in rows], [r for _, r in rows], marker, color=color,
                      mfc="none" if marker == "d" else color, label="grainflow MPM, " + label)
    ax.set_xlabel("aspect ratio a = H_i / L_i")
    ax.set_ylabel("run-out (L_f - L_i) / L_i")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
