#!/usr/bin/env python3
"""Draft, kiss and tumble of two grains, as the seed study's figure 5.15: δx/D, δy/D and the
gap δ = √(δx² + δy²)/D − 1 against t/√(D/g), from a run's grain probes.

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
    for k in ("dkt.kiss_time", "dkt.tumble_time", "dkt.separation_time", "dkt.min_gap"):
        if k in r:
            print(f"{k} = {r[k]:.2f}")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not installed: no picture")
        return
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(t, dx, label="δx / D")
    ax.plot(t, dy, label="δy / D")
    ax.plot(t, gap, label="gap δ / D")
    for k, style in (("dkt.kiss_time", ":"), ("dkt.tumble_time", "--")):
        if k in r and r[k] == r[k]:
            ax.axvline(r[k], color="grey", ls=style, lw=0.8)
            ax.text(r[k], ax.get_ylim()[1], k.split(".")[1].replace("_time", ""), fontsize=8, va="top")
    ax.axvline(25, color="red", ls="-.", lw=0.8)
    ax.text(25, ax.get_ylim()[0], " seed kiss (25)", color="red", fontsize=8, va="bottom")
    ax.set_xlabel("t / √(D/g)")
    ax.set_ylabel("distance / D")
    ax.set_title(summary.get("title", "draft, kiss and tumble"))
    ax.legend()
    ax.grid(alpha=0.3)
    out = a.out or str(run / "dkt.png")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
