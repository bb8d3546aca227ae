#!/usr/bin/env python3
"""Coupling robustness sweep: a disk settling from rest, for every coupling scheme, at 8, 16,
32 and 64 cells per diameter, grain-to-fluid density ratios 1.01, 1.5, 2.5 and 8, and
terminal Reynolds numbers from 1 to 500.

Each case is a scene written into the output folder (never into jobs/). The sweep runs
`grainflow check` on it, then `grainflow run`, and records what happened:

  refused   check refused the scene (its first error line is kept);
  finished  the run ended normally;
  unstable  the run stopped as unstable (exit 3) after check had passed it (a defect);
  failed    any other exit (a defect).

For finished runs it records the mean fall speed over the last fifth of the run, and its
error against the same case at the finest resolution that finished (the "converged value").

The scene: d = 2 mm, water (ρ = 1000 kg/m³, ν = 1e-6 m²/s), a channel 8 d wide with periodic
sides and walls below and above, 14 d tall; the disk starts 2 d below the top. Gravity is set
so that the 2-D terminal speed U_t = Re ν / d holds with White's cylinder drag
C_D = 1 + 10 Re^(-2/3):  g (ρ_s/ρ − 1) = 2 C_D U_t² / (π d). The lattice velocity of U_t is
`--lattice-velocity` (0.05), which sets Δt, and so τ = ½ + 3 u_lb N / Re. The run lasts 8 d of
fall at U_t (8 N / u_lb steps).

Usage:
  jobs/robustness/sweep.py --out runs/robustness [--bin target/release/grainflow]
                           [--threads 2] [--cells 8,16,32,64] [--ratios 1.01,1.5,2.5,8]
                           [--re 1,10,100,500] [--schemes bounce-back,interpolated,psm]
                           [--dry-run]
Writes OUT/results.csv and OUT/results.md (the table docs/validation.md quotes). A copy of
results.csv in jobs/robustness/ is the coupled stability map `grainflow check` judges coupled
scenes by (crates/stability/src/coupled.rs).
"""

import argparse
import csv
import math
import os
import subprocess
import sys
import time

D = 0.002
NU = 1.0e-6
RHO = 1000.0


def scene_text(scheme, cells, ratio, re, u_lb):
    """The scene of one case, as TOML."""
    u_t = re * NU / D
    c_d = 1.0 + 10.0 * re ** (-2.0 / 3.0)
    g = 2.0 * c_d * u_t * u_t / (math.pi * D) / (ratio - 1.0)
    dx = D / cells
    nx, ny = 8 * cells, 14 * cells
    steps = int(round(8 * cells / u_lb))
    probe_every = max(1, steps // 500)
    return f"""title = "robustness: {scheme}, {cells} cells per diameter, rho_s/rho = {ratio}, Re_t = {re}"

[domain]
cells = [{nx}, {ny}]
spacing_m = {dx!r}

[fluid]
density_kg_m3 = {RHO}
viscosity_m2_s = {NU}
reference_velocity_m_s = {u_t!r}
reference_length_m = {D}
lattice_velocity = {u_lb}
collision = {{ model = "trt" }}

[boundaries]
west = {{ kind = "periodic" }}
east = {{ kind = "periodic" }}
south = {{ kind = "wall" }}
north = {{ kind = "wall" }}

[grains]
density_kg_m3 = {RHO * ratio!r}
gravity_m_s2 = [0.0, {-g!r}]

[grains.contact]
normal_stiffness_n_m2 = 1.0e5
tangential_stiffness_n_m2 = 0.5e5
restitution = 0.5
friction = 0.3

[grains.sample]
kind = "list"
grains = [{{ position_m = [{4 * D!r}, {12 * D!r}], radius_m = {D / 2!r} }}]

[coupling]
scheme = "{scheme}"

[run]
steps = {steps}

[output]
probe_every_steps = {probe_every}
every_steps = {steps}
pictures = false

[[probes]]
kind = "grain"
name = "disk"
id = 0
"""


def fall_speed(probe_csv):
    """Mean downward speed (m/s) over the last fifth of the probe series."""
    with open(probe_csv) as f:
        rows = list(csv.DictReader(f))
    tail = rows[len(rows) * 4 // 5:]
    return -sum(float(r["vy_m_s"]) for r in tail) / len(tail)


def first_error(text):
    for line in text.splitlines():
        if line.startswith("error") or "likely unstable" in line:
            return line.strip()
    lines = [l for l in text.splitlines() if l.strip()]
    return lines[-1].strip() if lines else ""


def run_case(args, scheme, cells, ratio, re):
    name = f"{scheme}-n{cells}-r{ratio}-re{re}"
    folder = os.path.join(args.out, name)
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, "scene.toml")
    with open(path, "w") as f:
        f.write(scene_text(scheme, cells, ratio, re, args.lattice_velocity))
    tau = 0.5 + 3.0 * args.lattice_velocity * cells / re
    row = {"scheme": scheme, "cells": cells, "ratio": ratio, "re": re, "tau": f"{tau:.6f}",
           "lattice_velocity": args.lattice_velocity, "outcome": "", "reason": "",
           "fall_speed_m_s": "", "error": "", "seconds": ""}
    check = subprocess.run([args.bin, "check", path], capture_output=True, text=True)
    verdict = [l for l in check.stdout.splitlines() if l.strip().startswith("stability")]
    row["check"] = verdict[0].split(None, 1)[1] if verdict else ""
    if check.returncode != 0:
        row["outcome"], row["reason"] = "refused", first_error(check.stderr + check.stdout)
        return row
    if args.dry_run:
        row["outcome"] = "checked"
        return row
    start = time.time()
    out = os.path.join(folder, "out")
    run = subprocess.run([args.bin, "run", path, "--out", out, "--quiet",
                          "--threads", str(args.threads)], capture_output=True, text=True)
    row["seconds"] = f"{time.time() - start:.1f}"
    if run.returncode == 0:
        row["outcome"] = "finished"
        row["fall_speed_m_s"] = f"{fall_speed(os.path.join(out, 'probe_disk.csv')):.6e}"
    else:
        row["outcome"] = "unstable" if run.returncode == 3 else f"failed ({run.returncode})"
        row["reason"] = first_error(run.stderr)
    return row


def add_errors(rows):
    """Error of each finished run against the finest finished run of the same case."""
    finest = {}
    for r in rows:
        if r["outcome"] == "finished":
            key = (r["scheme"], r["ratio"], r["re"])
            if key not in finest or r["cells"] > finest[key]["cells"]:
                finest[key] = r
    for r in rows:
        ref = finest.get((r["scheme"], r["ratio"], r["re"]))
        if r["outcome"] == "finished" and ref is not None and ref is not r:
            v, v_ref = float(r["fall_speed_m_s"]), float(ref["fall_speed_m_s"])
            r["error"] = f"{(v - v_ref) / v_ref:+.3f} (vs {ref['cells']})"


def write_table(rows, path):
    with open(path, "w") as f:
        f.write("| scheme | cells per d | ρ_s/ρ | Re_t | outcome | fall speed (m/s) | "
                "error vs finest | check's fluid verdict | reason |\n")
        f.write("|---|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write(f"| {r['scheme']} | {r['cells']} | {r['ratio']} | {r['re']} | "
                    f"{r['outcome']} | {r['fall_speed_m_s']} | {r['error']} | "
                    f"{r['check']} | {r['reason']} |\n")


def write_map(rows, path):
    """The coupled stability map: one line per case that ran (refused ones say nothing)."""
    with open(path, "w") as f:
        f.write("scheme,cells_per_diameter,density_ratio,tau,lattice_velocity,stable\n")
        for r in rows:
            if r["outcome"] in ("finished", "unstable"):
                f.write(f"{r['scheme']},{r['cells']},{r['ratio']},{r['tau']},"
                        f"{r['lattice_velocity']},{int(r['outcome'] == 'finished')}\n")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True, help="folder for scenes and results")
    p.add_argument("--bin", default="target/release/grainflow")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--cells", default="8,16,32,64")
    p.add_argument("--ratios", default="1.01,1.5,2.5,8")
    p.add_argument("--re", default="1,10,100,500")
    p.add_argument("--schemes", default="bounce-back,interpolated,psm")
    p.add_argument("--lattice-velocity", type=float, default=0.05)
    p.add_argument("--dry-run", action="store_true", help="check only")
    args = p.parse_args()
    if not os.access(args.bin, os.X_OK):
        sys.exit(f"error: no grainflow binary at {args.bin} (build it, or give --bin)")
    if os.path.abspath(args.out).startswith(os.path.abspath("jobs") + os.sep):
        sys.exit("error: --out must not lie inside jobs/")
    cells = [int(c) for c in args.cells.split(",")]
    ratios = [float(r) for r in args.ratios.split(",")]
    res = [float(r) for r in args.re.split(",")]
    cases = [(s, n, r, re) for s in args.schemes.split(",") for r in ratios for re in res
             for n in cells]
    # Cell updates of the whole sweep, at about 300 M per second on 2 cores.
    updates = sum(8 * n * 14 * n * 8 * n / args.lattice_velocity for (_, n, _, _) in cases)
    print(f"{len(cases)} cases, about {updates / 3e8 / 60:.0f} min at 300 MLUPS", flush=True)
    rows = []
    for case in cases:
        row = run_case(args, *case)
        rows.append(row)
        print(f"{row['scheme']:>12} n={row['cells']:<3} ratio={row['ratio']:<5} "
              f"Re={row['re']:<6} {row['outcome']:<9} {row['fall_speed_m_s']:>13} "
              f"{row['seconds']:>6}s {row['reason'][:100]}", flush=True)
    add_errors(rows)
    fields = ["scheme", "cells", "ratio", "re", "tau", "lattice_velocity", "outcome",
              "fall_speed_m_s", "error", "check", "reason", "seconds"]
    with open(os.path.join(args.out, "results.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    write_table(rows, os.path.join(args.out, "results.md"))
    write_map(rows, os.path.join(args.out, "coupled-map.csv"))
    bad = [r for r in rows if r["outcome"] not in ("finished", "refused", "checked")]
    print(f"{len(bad)} of {len(rows)} runs blew up or failed after check passed them")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
