#!/usr/bin/env python3
"""Draft, kiss and tumble of two grains, as the seed study's figure 5.15: δx/D, δy/D and the
gap δ = √(δx² + δy²)/D − 1 against t/√(D/g), from a run's grain probes. When the scene's
draft-kiss-tumble analysis gives `terminal_velocity_m_s` (one disk alone in the channel), a
second panel draws both grains' fall speeds over it, with the ±5 % band and `fall_window_s`.

    python3 scripts/plot-dkt.py RUN [--lower lower] [--upper upper] [--out dkt.png]

RUN is a run folder with probe_<lower>.csv and probe_<upper>.csv (grain probes). Prints the
kiss, tumble and separation times; draws the PNG with matplotlib when it is installed.
"""
import argparse
import csv
import json
import math
import pathlib


def load(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return [{k: float(v) for k, v in r.items()} for r in rows]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run")
    ap.add_argument("--lower", default="lower")
    ap.add_argument("--upper", default="upper")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    run = pathlib.Path(a.run)
    summary = json.loads((run / "summary.json").read_text())
    grains = summary["scene"]["grains"]
    g = math.hypot(*grains["gravity_m_s2"])
    listed = grains["sample"]["grains"]
    d = listed[0]["radius_m"] + listed[1]["radius_m"]
    unit = math.sqrt(d / g)
    lo, up = load(run / f"probe_{a.lower}.csv"), load(run / f"probe_{a.upper}.csv")
    n = min(len(lo), len(up))
    t = [lo[i]["time_s"] / unit for i in range(n)]
    dx = [(up[i]["x_m"] - lo[i]["x_m"]) / d for i in range(n)]
    dy = [(up[i]["y_m"] - lo[i]["y_m"]) / d for i in range(n)]
    gap = [math.hypot(dx[i], dy[i]) - 1.0 for i in range(n)]
    r = summary.get("results", {})
    dkt = next((x for x in summary["scene"].get("analyses", []) if x.get("kind") == "draft-kiss-tumble"), {})
    ut = dkt.get("terminal_velocity_m_s")
    gv = grains["gravity_m_s2"]
    down = (gv[0] / g, gv[1] / g)
    fall = [[(p[i]["vx_m_s"] * down[0] + p[i]["vy_m_s"] * down[1]) / ut for i in range(n)] for p in (lo, up)] if ut else None
    for k in (
        "dkt.kiss_time",
        "dkt.tumble_time",
        "dkt.separation_time",
        "dkt.second_kiss_time",
        "dkt.min_gap",
        "dkt.leader_fall_deviation",
        "dkt.trailer_fall_deviation",
    ):
        if k in r:
            # summary.json writes a result that did not happen (NaN) as null.
            print(f"{k} = {r[k]:.3f}" if r[k] is not None else f"{k}: none")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not installed: no picture")
        return
    if fall:
        fig, (ax, bx) = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
    else:
        fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(t, dx, label="δx / D")
    ax.plot(t, dy, label="δy / D")
    ax.plot(t, gap, label="gap δ / D")
    marks = (("dkt.kiss_time", ":"), ("dkt.tumble_time", "--"), ("dkt.second_kiss_time", ":"))
    for k, style in marks:
        if r.get(k) is not None and r[k] == r[k]:
            ax.axvline(r[k], color="grey", ls=style, lw=0.8)
            label = k.split(".")[1].replace("_time", "").replace("_", " ")
            ax.text(r[k], ax.get_ylim()[1], label, fontsize=8, va="top")
    ax.axvline(25, color="red", ls="-.", lw=0.8)
    ax.text(25, ax.get_ylim()[0], " seed kiss (25)", color="red", fontsize=8, va="bottom")
    ax.set_ylabel("distance / D")
    ax.set_title(summary.get("title", "draft, kiss and tumble"))
    ax.legend()
    ax.grid(alpha=0.3)
    if fall:
        bx.plot(t, fall[0], label=f"{a.lower} (starts below)")
        bx.plot(t, fall[1], label=f"{a.upper} (starts above)")
        bx.axhspan(0.95, 1.05, color="green", alpha=0.12, label="±5 % of one disk alone")
        bx.axhline(1.0, color="green", lw=0.8)
        w = dkt.get("fall_window_s")
        if w:
            bx.axvspan(w[0] / unit, w[1] / unit, color="grey", alpha=0.15, label="fall window")
        for k, style in marks:
            if r.get(k) is not None and r[k] == r[k]:
                bx.axvline(r[k], color="grey", ls=style, lw=0.8)
        bx.set_ylabel(f"fall speed / U_t (U_t = {ut:.4g} m/s)")
        bx.set_xlabel("t / √(D/g)")
        bx.legend(fontsize=8)
        bx.grid(alpha=0.3)
    else:
        ax.set_xlabel("t / √(D/g)")
    out = a.out or str(run / "dkt.png")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
