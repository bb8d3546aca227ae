#!/usr/bin/env python3
"""Table of the submerged column collapses against their dry twins (jobs/submerged-collapse).

Usage: scripts/submerged-table.py RUNS_DIR
Reads RUNS_DIR/{sub,dry}-a<A>-<packing>/summary.json and prints, per a and packing: the
column's packing fraction, the run-out (L_f - L_i)/L_i dry and submerged, their ratio, the
time to 95 % of the run-out in tau_c = sqrt(H_i/g), and the extremes of the excess pore
pressure under the column.
"""
import json
import os
import sys


def load(d):
    try:
        with open(os.path.join(d, "summary.json")) as f:
            return json.load(f)
    except FileNotFoundError:
        return None


def main():
    runs = sys.argv[1]
    print("|   a | packing | φ (2-D) | run-out dry | run-out submerged | sub/dry | t₉₅/τ_c dry | t₉₅/τ_c sub | pore p min / max (Pa) |")
    print("|----:|---------|--------:|------------:|------------------:|--------:|------------:|------------:|----------------------:|")
    for a in ["a0.5", "a1", "a2"]:
        for p in ["loose", "dense"]:
            sub, dry = load(f"{runs}/sub-{a}-{p}"), load(f"{runs}/dry-{a}-{p}")
            if sub is None or dry is None:
                print(f"| {a[1:]} | {p} | (not run) |")
                continue
            rs, rd = sub["results"], dry["results"]
            if sub["status"] not in ("ok", "checks-failed"):
                print(f"| {a[1:]} | {p} | submerged run {sub['status']}: {sub.get('error')} |")
                continue
            ratio = rs["collapse.runout"] / rd["collapse.runout"]
            print(
                f"| {rs['collapse.aspect_ratio']:.2f} | {p} | {rs['collapse.packing_fraction']:.3f} "
                f"| {rd['collapse.runout']:.3f} | {rs['collapse.runout']:.3f} | {ratio:.2f} "
                f"| {rd.get('collapse.front_t95', float('nan')):.1f} | {rs.get('collapse.front_t95', rs['collapse.stop_time']):.1f} "
                f"| {rs['collapse.pore_pressure_min_pa']:+.1f} / {rs['collapse.pore_pressure_max_pa']:+.1f} |"
            )


if __name__ == "__main__":
    main()
