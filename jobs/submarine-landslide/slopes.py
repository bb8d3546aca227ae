#!/usr/bin/env python3
"""The landslide at several slope angles: dry against submerged, loose against dense.

For each slope angle, writes the scenes of one size with make-scenes.py, runs the four of
them (sub/dry x loose/dense) and gathers from their summaries the run-out, the front's
start (t10), duration (t95) and mean speed, the excess pore pressure under the mass and the
grains' peak kinetic energy. Writes OUT/results.csv, OUT/results.md and, when matplotlib is
there, OUT/front.png (the front's position against time per angle) and OUT/energy.png (the
grains' kinetic energy against time, and the fluid's in the submerged runs), dry against
submerged, loose against dense.

Usage: slopes.py --out DIR [--slopes 5 12 20] [--size small] [--grainflow PATH]
       slopes.py --out DIR --plot-only     (tables and plot from finished runs)
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
CASES = ["sub-loose", "sub-dense", "dry-loose", "dry-dense"]
KEYS = [
    ("runout", "collapse.runout"),
    ("t10_tc", "collapse.front_t10"),
    ("t95_tc", "collapse.front_t95"),
    ("front_speed_m_s", "collapse.front_speed_m_s"),
    ("packing_fraction", "collapse.packing_fraction"),
    ("pore_min_pa", "collapse.pore_pressure_min_pa"),
    ("pore_max_pa", "collapse.pore_pressure_max_pa"),
]


def scene_name(case, size):
    medium, packing = case.split("-")
    return f"{medium}-{size}-{packing}"


def run_all(args):
    for theta in args.slopes:
        d = os.path.join(args.out, f"slope-{theta:g}")
        os.makedirs(d, exist_ok=True)
        subprocess.run(
            [sys.executable, os.path.join(HERE, "make-scenes.py"), "--out", d, "--slope", str(theta)],
            check=True,
        )
        for case in CASES:
            name = scene_name(case, args.size)
            out = os.path.join(d, name)
            print(f"slope {theta:g} deg: {name}", flush=True)
            r = subprocess.run(
                [args.grainflow, "run", os.path.join(d, name + ".toml"), "--out", out, "--quiet"]
            )
            if r.returncode not in (0, 2):
                print(f"  {name} exited {r.returncode}", file=sys.stderr)


def gather(args):
    rows = []
    for theta in args.slopes:
        d = os.path.join(args.out, f"slope-{theta:g}")
        for case in CASES:
            path = os.path.join(d, scene_name(case, args.size), "summary.json")
            if not os.path.exists(path):
                continue
            s = json.load(open(path))
            res = s.get("results", {})
            row = {"slope_deg": theta, "case": case, "status": s["status"]}
            for k, key in KEYS:
                v = res.get(key)
                row[k] = float("nan") if v is None else float(v)
            _, grains, _ = energy_series(os.path.dirname(path), case)
            row["peak_grain_ke_j_m"] = max(grains) if grains else float("nan")
            rows.append(row)
    return rows


def write_tables(args, rows):
    with open(os.path.join(args.out, "results.csv"), "w", newline="") as f:
        names = ["slope_deg", "case", "status"] + [k for k, _ in KEYS] + ["peak_grain_ke_j_m"]
        w = csv.DictWriter(f, fieldnames=names)
        w.writeheader()
        w.writerows(rows)
    fmt = lambda v, p: "–" if v is None or math.isnan(v) else f"{v:.{p}f}"
    lines = [
        "| slope | case | run-out | t10/τc | t95/τc | front speed (m/s) | φ | pore p min / max (Pa) "
        "| peak grain KE (mJ/m) |",
        "|---:|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        pore = (
            "–"
            if math.isnan(r["pore_min_pa"])
            else f"{r['pore_min_pa']:.1f} / {r['pore_max_pa']:.1f}"
        )
        lines.append(
            f"| {r['slope_deg']:g}° | {r['case']} | {fmt(r['runout'], 3)} | {fmt(r['t10_tc'], 1)} "
            f"| {fmt(r['t95_tc'], 1)} | {fmt(r['front_speed_m_s'], 3)} "
            f"| {fmt(r['packing_fraction'], 3)} | {pore} | {fmt(r['peak_grain_ke_j_m'] * 1e3, 3)} |"
        )
    open(os.path.join(args.out, "results.md"), "w").write("\n".join(lines) + "\n")
    print("\n".join(lines))


def front_series(run_dir, case):
    """(t, front) of a run: the deposit probe of a submerged run, front.csv of a dry one."""
    name = "probe_front.csv" if case.startswith("sub") else "front.csv"
    path = os.path.join(run_dir, name)
    if not os.path.exists(path):
        return [], []
    rows = list(csv.DictReader(open(path)))
    return [float(r["time_s"]) for r in rows], [float(r["front_m"]) for r in rows]


def energy_series(run_dir, case):
    """(t, grain KE, fluid KE) in J/m: the kinetic-energy probe of a submerged run,
    front.csv of a dry one (no fluid)."""
    if case.startswith("sub"):
        path, grains, fluid = os.path.join(run_dir, "probe_energy.csv"), "grains_j_m", "fluid_j_m"
    else:
        path, grains, fluid = os.path.join(run_dir, "front.csv"), "kinetic_energy_j_m", None
    if not os.path.exists(path):
        return [], [], []
    rows = list(csv.DictReader(open(path)))
    t = [float(r["time_s"]) for r in rows]
    return t, [float(r[grains]) for r in rows], [float(r[fluid]) for r in rows] if fluid else []


STYLE = {
    "sub-loose": ("tab:blue", "-"),
    "sub-dense": ("tab:blue", "--"),
    "dry-loose": ("tab:orange", "-"),
    "dry-dense": ("tab:orange", "--"),
}


def plot_energy(args, plt):
    n = len(args.slopes)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 3.6), sharey=True, squeeze=False)
    for ax, theta in zip(axes[0], args.slopes):
        d = os.path.join(args.out, f"slope-{theta:g}")
        for case in CASES:
            t, grains, fluid = energy_series(os.path.join(d, scene_name(case, args.size)), case)
            c, ls = STYLE[case]
            if t:
                ax.plot(t, [v * 1e3 for v in grains], color=c, linestyle=ls, label=case)
            if fluid:
                ax.plot(t, [v * 1e3 for v in fluid], color="tab:green", linestyle=ls,
                        label=f"{case} (fluid)")
        ax.set_title(f"slope {theta:g}°")
        ax.set_xlabel("time (s)")
        ax.set_yscale("symlog", linthresh=1e-3)
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("kinetic energy (mJ per m of depth)")
    axes[0][0].legend(fontsize=7)
    fig.suptitle(f"grains' kinetic energy, {args.size} size: dry (orange), submerged (blue); "
                 "the fluid's (green)")
    fig.tight_layout()
    path = os.path.join(args.out, "energy.png")
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def plot(args):
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot (pip install matplotlib)")
        return
    n = len(args.slopes)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 3.6), sharey=True, squeeze=False)
    style = STYLE
    for ax, theta in zip(axes[0], args.slopes):
        d = os.path.join(args.out, f"slope-{theta:g}")
        for case in CASES:
            t, x = front_series(os.path.join(d, scene_name(case, args.size)), case)
            if t:
                c, ls = style[case]
                ax.plot(t, [v * 1e3 for v in x], color=c, linestyle=ls, label=case)
        ax.set_title(f"slope {theta:g}°")
        ax.set_xlabel("time (s)")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("front (mm from the back wall)")
    axes[0][0].legend(fontsize=8)
    fig.suptitle(f"landslide front, {args.size} size: dry (orange) and submerged (blue)")
    fig.tight_layout()
    path = os.path.join(args.out, "front.png")
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")
    plot_energy(args, plt)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", required=True)
    p.add_argument("--slopes", type=float, nargs="+", default=[5.0, 12.0, 20.0])
    p.add_argument("--size", default="small", choices=["small", "medium"])
    p.add_argument("--grainflow", default=os.path.join(ROOT, "target/release/grainflow"))
    p.add_argument("--plot-only", action="store_true")
    args = p.parse_args()
    if not args.plot_only:
        run_all(args)
    write_tables(args, gather(args))
    plot(args)


if __name__ == "__main__":
    main()
