#!/usr/bin/env python3
"""Permeability of periodic square arrays of fixed disks: Stokes flow through one disk in a
periodic square cell, against the drag of Sangani & Acrivos (1982, Table 1).

Each case is a scene written into the output folder (never into jobs/): a periodic cell of
L x L lattice cells holding one fixed disk (`fixed = true`) whose hydrodynamic radius r_h
gives the solid fraction c = pi r_h^2 / L^2, water (nu = 1e-6 m^2/s), driven by a body
acceleration G along x (the same velocity field as a pressure gradient -dp/dx = rho G).
The `permeability` analysis gives the superficial velocity U, Darcy's k = nu U / G and the
drag K = F / (mu U) = G L^2 / (nu U), compared with the table.

G is set for a Reynolds number U (2 r_h) / nu of about 0.1 at the reference drag (Stokes
flow), and the run lasts ten times the slower of the two relaxation times: the mean
flow's k / nu and the cell's viscous time L^2 / (4 pi^2 nu).

The hydrodynamic radius ratio r_h / r (issue 52) changes what the fluid sees, not the
contacts: at a fixed contact packing (c of the contact radius), a smaller r_h opens the
pores. `--ratios` sweeps it at the fixed contact solid fraction `--contact-fraction`.

Usage:
  jobs/permeability/sweep.py --out runs/permeability [--bin target/release/grainflow]
        [--threads 2] [--fractions 0.05,0.1,0.2,0.3,0.4,0.5] [--cells 8,16,32,64]
        [--schemes bounce-back,interpolated,psm] [--tau 1.0]
        [--ratios 1,0.9,0.8,0.7] [--contact-fraction 0.5] [--ratio-cells 16]
Writes OUT/results.csv, OUT/results.md (the tables docs/validation.md quotes).
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

NU = 1.0e-6
D = 1.6e-3  # contact diameter of the disk (m) at 1 ratio

# Sangani & Acrivos (1982), Table 1: K = F / (mu U) on a square array at solid fraction c.
TABLE = [(0.05, 15.56), (0.10, 24.83), (0.20, 51.53), (0.30, 102.90), (0.40, 217.89),
         (0.50, 532.55), (0.60, 1.763e3), (0.70, 1.352e4), (0.75, 1.263e5)]


def reference_drag(c):
    for (c0, k0), (c1, k1) in zip(TABLE, TABLE[1:]):
        if c0 <= c <= c1:
            s = (c - c0) / (c1 - c0)
            return math.exp(math.log(k0) * (1 - s) + math.log(k1) * s)
    return 4 * math.pi / (-0.5 * math.log(c) - 0.738 + c - 0.887 * c * c + 2.038 * c ** 3)


def case(c_h, cells, ratio):
    """Lattice size, spacing, contact radius and the hydrodynamic solid fraction of a case
    whose hydrodynamic diameter is `cells` lattice cells at hydrodynamic fraction `c_h`."""
    dx = D * ratio / cells
    n = round(math.sqrt(math.pi * (cells / 2) ** 2 / c_h))
    r_h = math.sqrt(c_h / math.pi) * n * dx
    return n, dx, r_h / ratio


def scene_text(scheme, c_h, cells, ratio, tau):
    n, dx, r = case(c_h, cells, ratio)
    length = n * dx
    r_h = r * ratio
    k = math.pi * r_h * r_h / (c_h * reference_drag(c_h))
    u = 0.1 * NU / (2 * r_h)
    g = NU * u / k
    end = 10 * max(k, length * length / (4 * math.pi ** 2)) / NU
    return f"""title = "permeability: {scheme}, c = {c_h}, {cells} cells per hydrodynamic diameter, r_h/r = {ratio}"

[domain]
cells = [{n}, {n}]
spacing_m = {dx!r}

[fluid]
density_kg_m3 = 1000.0
viscosity_m2_s = {NU}
reference_velocity_m_s = {u!r}
reference_length_m = {2 * r_h!r}
relaxation_time = {tau}
body_acceleration_m_s2 = [{g!r}, 0.0]
collision = {{ model = "trt" }}

[boundaries]
west = {{ kind = "periodic" }}
east = {{ kind = "periodic" }}
south = {{ kind = "periodic" }}
north = {{ kind = "periodic" }}

[grains]
density_kg_m3 = 2500.0
gravity_m_s2 = [0.0, 0.0]

[grains.contact]
normal_stiffness_n_m2 = 1.0e5
tangential_stiffness_n_m2 = 0.5e5
restitution = 0.5
friction = 0.3

[grains.sample]
kind = "list"
grains = [{{ position_m = [{length / 2!r}, {length / 2!r}], radius_m = {r!r}, fixed = true }}]

[coupling]
scheme = "{scheme}"
hydrodynamic_radius_ratio = {ratio}

[run]
end_time_s = {end!r}

[output]
pictures = false

[[analyses]]
kind = "permeability"
"""


def run_case(args, scheme, c_h, cells, ratio):
    name = f"{scheme}-c{c_h}-n{cells}-rh{ratio}"
    folder = os.path.join(args.out, name)
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, "scene.toml")
    with open(path, "w") as f:
        f.write(scene_text(scheme, c_h, cells, ratio, args.tau))
    row = {"scheme": scheme, "solid_fraction": c_h, "cells": cells, "ratio": ratio,
           "tau": args.tau, "outcome": "", "drag_factor": "", "reference": "",
           "deviation": "", "permeability_m2": "", "k_over_r2": "", "reynolds": "",
           "seconds": ""}
    start = time.time()
    out = os.path.join(folder, "out")
    run = subprocess.run([args.bin, "run", path, "--out", out, "--quiet",
                          "--threads", str(args.threads)], capture_output=True, text=True)
    row["seconds"] = f"{time.time() - start:.1f}"
    if run.returncode != 0:
        row["outcome"] = f"failed ({run.returncode}): " + run.stderr.strip().splitlines()[-1]
        return row
    with open(os.path.join(out, "summary.json")) as f:
        res = json.load(f)["results"]
    k_ref = reference_drag(res["permeability.solid_fraction"])
    row.update(outcome="finished",
               drag_factor=f"{res['permeability.drag_factor']:.2f}",
               reference=f"{k_ref:.2f}",
               deviation=f"{res['permeability.drag_factor'] / k_ref - 1:+.3f}",
               permeability_m2=f"{res['permeability.permeability_m2']:.4e}",
               k_over_r2=f"{res['permeability.permeability_m2'] / case(c_h, cells, ratio)[2] ** 2:.4f}",
               reynolds=f"{res['permeability.reynolds']:.3f}")
    return row


def write_tables(rows, path):
    with open(path, "w") as f:
        f.write("| scheme | c (r_h) | cells per d_h | r_h/r | K = F/(μU) | Sangani–Acrivos | "
                "deviation | k (m²) | k / r² | Re |\n|---|---|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write(f"| {r['scheme']} | {r['solid_fraction']} | {r['cells']} | {r['ratio']} | "
                    f"{r['drag_factor'] or r['outcome']} | {r['reference']} | "
                    f"{r['deviation']} | {r['permeability_m2']} | {r['k_over_r2']} | "
                    f"{r['reynolds']} |\n")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True, help="folder for scenes and results")
    p.add_argument("--bin", default="target/release/grainflow")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--fractions", default="0.05,0.1,0.2,0.3,0.4,0.5")
    p.add_argument("--cells", default="8,16,32,64")
    p.add_argument("--schemes", default="bounce-back,interpolated,psm")
    p.add_argument("--tau", type=float, default=1.0)
    p.add_argument("--ratios", default="1,0.9,0.8,0.7")
    p.add_argument("--contact-fraction", type=float, default=0.5)
    p.add_argument("--ratio-cells", type=int, default=16)
    args = p.parse_args()
    if not os.access(args.bin, os.X_OK):
        sys.exit(f"error: no grainflow binary at {args.bin} (build it, or give --bin)")
    if os.path.abspath(args.out).startswith(os.path.abspath("jobs") + os.sep):
        sys.exit("error: --out must not lie inside jobs/")
    schemes = args.schemes.split(",")
    cases = [(s, float(c), int(n), 1.0) for s in schemes for c in args.fractions.split(",")
             for n in args.cells.split(",")]
    # The r_h sweep: the contact packing fixed, the fluid's fraction c (r_h/r)^2.
    for ratio in (float(x) for x in args.ratios.split(",") if float(x) != 1.0):
        c_h = round(args.contact_fraction * ratio * ratio, 6)
        cases += [(s, c_h, args.ratio_cells, ratio) for s in schemes]
    cases += [(s, args.contact_fraction, args.ratio_cells, 1.0) for s in schemes
              if (s, args.contact_fraction, args.ratio_cells, 1.0) not in cases]
    print(f"{len(cases)} cases", flush=True)
    rows = []
    for c in cases:
        row = run_case(args, *c)
        rows.append(row)
        print(f"{row['scheme']:>12} c={row['solid_fraction']:<7} n={row['cells']:<3} "
              f"r_h/r={row['ratio']:<4} K={row['drag_factor']:>8} ref={row['reference']:>8} "
              f"{row['deviation']:>7} {row['seconds']:>6}s {row['outcome'][:80]}", flush=True)
    with open(os.path.join(args.out, "results.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    write_tables(rows, os.path.join(args.out, "results.md"))
    bad = [r for r in rows if r["outcome"] != "finished"]
    print(f"{len(bad)} of {len(rows)} runs failed")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
