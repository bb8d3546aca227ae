#!/usr/bin/env python3
"""Run-out of the column-collapse sweep against the published laws.

Reads runs/column-collapse/a<a>[-s<seed>]/summary.json (written by jobs/column-collapse/run.sh),
averages the packings (seeds) of each aspect ratio, prints a table of (L_f - L_i)/L_i and H_f/L_i
against the 2-D DEM law and the experiments (../shared/reference/README.md), fits the exponents
of both regimes (split at the DEM law's transition a = 2.7), locates the transition where the
local exponent falls below 1 (as the published laws define it), and draws run-out vs a on log axes
with the reference lines (matplotlib; the table is printed without it).
"""
import argparse
import glob
import json
import math
import os

EXP = (1.2, 1.9, 2.3)   # Lajeunesse et al. 2005: 1.2 a below a ~ 2.3, 1.9 a^(2/3) above
DEM = (1.67, 2.7, 2.7)  # published 2-D DEM of disks: 1.67 a below a ~ 2.7, 2.7 a^(2/3) above


def law(a, c):
    lin, pow_, t = c
    return lin * a if a < t else pow_ * a ** (2 / 3)


def fit(points):
    """Least-squares slope of log(runout) vs log(a)."""
    xs = [math.log(a) for a, _ in points]
    ys = [math.log(r) for _, r in points]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def local_exponent_transition(rows):
    """Where the local exponent d ln(run-out) / d ln(a) falls below 1: the transition as the
    published laws define it (exponent 1 below their stated transition, 2/3 above). Returns
    (linear interpolation between the exponents of neighbouring a, the same from a quadratic
    fit of ln(run-out) in ln(a)), or None."""
    xs = [math.log(a) for a, *_ in rows]
    ys = [math.log(r) for _, r, *_ in rows]
    if len(xs) < 3:
        return None
    loc = [(ys[i + 1] - ys[i]) / (xs[i + 1] - xs[i]) for i in range(len(xs) - 1)]
    mid = [(xs[i + 1] + xs[i]) / 2 for i in range(len(xs) - 1)]
    pair = None
    for i in range(len(loc) - 1):
        if loc[i] >= 1 > loc[i + 1]:
            pair = math.exp(mid[i] + (loc[i] - 1) / (loc[i] - loc[i + 1]) * (mid[i + 1] - mid[i]))
            break
    # Quadratic least squares y = c0 + c1 x + c2 x^2 (normal equations), slope 1 at x*.
    n = len(xs)
    sx = [sum(x ** k for x in xs) for k in range(5)]
    sxy = [sum(y * x ** k for x, y in zip(xs, ys)) for k in range(3)]
    m = [[sx[i + j] for j in range(3)] for i in range(3)]
    m[0][0] = n
    det = lambda q: (q[0][0] * (q[1][1] * q[2][2] - q[1][2] * q[2][1])
                     - q[0][1] * (q[1][0] * q[2][2] - q[1][2] * q[2][0])
                     + q[0][2] * (q[1][0] * q[2][1] - q[1][1] * q[2][0]))
    d = det(m)
    c = []
    for k in range(3):
        q = [row[:] for row in m]
        for i in range(3):
            q[i][k] = sxy[i]
        c.append(det(q) / d)
    quad = math.exp((1 - c[1]) / (2 * c[2])) if c[2] < 0 else None
    if pair is None or quad is None:
        return None
    return pair, quad


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("runs", help="folder with one run folder per aspect ratio")
    p.add_argument("--out", default=None, help="PNG to write")
    args = p.parse_args()
    groups = {}
    for f in sorted(glob.glob(os.path.join(args.runs, "*", "summary.json"))):
        name = os.path.basename(os.path.dirname(f)).split("-s")[0]
        r = json.load(open(f))
        groups.setdefault(name, []).append(r)
    rows = []
    for name, runs in groups.items():
        res = [r["results"] for r in runs]
        mean = lambda k: sum(x[k] for x in res) / len(res)
        std = lambda k: (sum((x[k] - mean(k)) ** 2 for x in res) / max(len(res) - 1, 1)) ** 0.5
        rows.append((mean("collapse.aspect_ratio"), mean("collapse.runout"), std("collapse.runout"),
                     mean("collapse.final_height"), mean("collapse.stop_time"),
                     sum(r["grains"] for r in runs) // len(runs), len(runs)))
    rows.sort()
    print(f"{'a':>6} {'grains':>7} {'runs':>4} {'runout':>14} {'DEM law':>8} {'dev':>7} {'exp.':>7} {'dev':>7} {'H_f/L_i':>8} {'t_stop/tau_c':>12}")
    for a, r, sd, h, t, n, k in rows:
        d, e = law(a, DEM), law(a, EXP)
        print(f"{a:6.2f} {n:7d} {k:4d} {r:7.3f} ± {sd:5.3f} {d:8.3f} {100*(r/d-1):+6.1f}% {e:7.3f} {100*(r/e-1):+6.1f}% {h:8.3f} {t:12.2f}")
    low = [(a, r) for a, r, *_ in rows if a < DEM[2]]
    high = [(a, r) for a, r, *_ in rows if a > DEM[2]]
    if len(low) >= 2:
        print(f"exponent below the transition (a < {DEM[2]}): {fit(low):.3f} (published ~1)")
    if len(high) >= 2:
        print(f"exponent above the transition (a > {DEM[2]}): {fit(high):.3f} (published ~2/3)")
    away = [(a, r) for a, r, *_ in rows if a >= 1.45 * DEM[2]]
    if len(away) >= 2 and len(away) < len(high):
        print(f"exponent above, away from the crossover (a >= {1.45 * DEM[2]:.1f}): {fit(away):.3f}")
    if len(low) >= 2 and len(high) >= 2:
        # Intersection of the two fitted power laws.
        sl, sh = fit(low), fit(high)
        cl = sum(math.log(r) - sl * math.log(a) for a, r in low) / len(low)
        ch = sum(math.log(r) - sh * math.log(a) for a, r in high) / len(high)
        if abs(sl - sh) > 1e-9:
            print(f"fitted branches intersect at a = {math.exp((ch - cl) / (sl - sh)):.2f} "
                  f"(the published laws' own branches: {(EXP[1] / EXP[0]) ** 3:.2f} experiments, "
                  f"{(DEM[1] / DEM[0]) ** 3:.2f} 2-D DEM)")
    t = local_exponent_transition(rows)
    if t:
        print(f"transition (local exponent falls below 1): a = {t[0]:.2f} between neighbours, "
              f"{t[1]:.2f} from a quadratic fit (published 1.8-3; the laws' own: {EXP[2]}, {DEM[2]})")
    if args.out:
        try:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError:
            print("matplotlib not installed: no plot")
            return
        a = [10 ** (k / 50) for k in range(-30, 66)]
        plt.figure(figsize=(6, 4.5))
        plt.loglog(a, [law(x, DEM) for x in a], "k-", label="2-D DEM law (1.67a; 2.7a$^{2/3}$)")
        plt.loglog(a, [law(x, EXP) for x in a], "k--", label="experiments (1.2a; 1.9a$^{2/3}$)")
        plt.errorbar([r[0] for r in rows], [r[1] for r in rows], yerr=[r[2] for r in rows],
                     fmt="o", color="C3", label="grainflow DEM (mean ± sd over packings)")
        plt.xlabel("aspect ratio a = H$_i$/L$_i$")
        plt.ylabel("run-out (L$_f$ - L$_i$)/L$_i$")
        plt.legend()
        plt.grid(True, which="both", alpha=0.3)
        plt.tight_layout()
        plt.savefig(args.out, dpi=120)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
