#!/usr/bin/env python3
"""Fresh lid-driven cavities written as a user would (not the map's runs): does
`grainflow check`'s stability verdict predict what `grainflow run` does?

Each cavity has U = 0.1 m/s, u_lb = 0.1 (Ma 0.17), N x N cells of 1 mm, and the viscosity
that gives the relaxation time asked; it runs 20 000 steps (twice the map's runs). A run
counts as stable when it finishes (exit 0) with every speed below 1.5 U at every snapshot
(every 2000 steps; the map looks every 100): the map's criterion. The verdict compared is check's for the cavity (a
wall-driven flow): "stable in wall-driven (cavity) flow" or "inside the stable region".
The largest speed is read from every snapshot of fields.h5 (every 2000 steps) with h5dump.

Usage: jobs/stability/user-cavities.py [--bin target/release/grainflow] [--out DIR]
Prints a markdown table and the count of right verdicts.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

# (N, tau, operator, Smagorinsky constant or None)
CASES = [
    (64, 0.512, "bgk", None), (64, 0.52, "bgk", None), (128, 0.515, "bgk", None),
    (128, 0.525, "bgk", None), (64, 0.515, "mrt", None), (64, 0.53, "mrt", None),
    (128, 0.52, "mrt", None), (128, 0.54, "mrt", None), (64, 0.505, "bgk", 0.1),
    (128, 0.51, "bgk", 0.1), (64, 0.505, "mrt", 0.1), (128, 0.512, "mrt", 0.1),
    (64, 0.503, "bgk", 0.17), (128, 0.505, "mrt", 0.17),
]
U = 0.1


def scene(n, tau, op, cs):
    dx = 0.001
    # u_lb = U dt / dx = 0.1 -> dt = 1e-3 s; nu = (tau - 1/2)/3 dx^2/dt.
    nu = (tau - 0.5) / 3.0 * dx * dx / 1e-3
    smag = f"smagorinsky_constant = {cs}\n" if cs else ""
    return f'''title = "cavity N = {n}, tau = {tau}, {op}{f", C_s = {cs}" if cs else ""}"
[domain]
cells = [{n}, {n}]
spacing_m = {dx}
[fluid]
density_kg_m3 = 1000.0
viscosity_m2_s = {nu:.9e}
reference_velocity_m_s = {U}
reference_length_m = {n * dx}
lattice_velocity = 0.1
collision = {{ model = "{op}" }}
{smag}[boundaries]
west = {{ kind = "wall" }}
east = {{ kind = "wall" }}
south = {{ kind = "wall" }}
north = {{ kind = "moving-wall", velocity_m_s = [{U}, 0.0] }}
[run]
steps = 20000
[output]
every_steps = 2000
pictures = false
fields = ["velocity"]
'''


def peak_speed(h5):
    """The largest |u| (m/s) over the snapshots of `h5`, NaN when there is none."""
    try:
        groups = subprocess.run(["h5ls", h5], capture_output=True, text=True).stdout.split()
    except OSError:
        sys.exit("h5ls and h5dump are needed (apt install hdf5-tools; scripts/setup.sh does)")
    peak = float("nan")
    for g in (g for g in groups if g.startswith("step_")):
        dump = subprocess.run(["h5dump", "-d", f"/{g}/velocity", "-y", "-w", "0", h5],
                              capture_output=True, text=True).stdout
        body = dump[dump.find("DATA {") + 6:]
        body = body[:body.find("}")]  # the attributes (time, step) follow
        v = [float(x) for x in re.findall(r"-?\d+\.?\d*(?:[eE][-+]?\d+)?", body)]
        for k in range(0, len(v) - 2, 3):
            s = (v[k] ** 2 + v[k + 1] ** 2) ** 0.5
            if not s <= peak:
                peak = s
    return peak


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--bin", default="target/release/grainflow")
    p.add_argument("--out", default=None)
    a = p.parse_args()
    out = a.out or tempfile.mkdtemp(prefix="user-cavities-")
    os.makedirs(out, exist_ok=True)
    print("| N | τ | operator | check (cavity) | run | max speed / U | right |")
    print("|---|---|---|---|---|---|---|")
    right = 0
    for n, tau, op, cs in CASES:
        name = f"n{n}-tau{tau}-{op}" + (f"-cs{cs}" if cs else "")
        path = os.path.join(out, name + ".toml")
        with open(path, "w") as f:
            f.write(scene(n, tau, op, cs))
        text = subprocess.run([a.bin, "check", path], capture_output=True, text=True).stdout
        line = next((l for l in text.splitlines() if "stability" in l), "")
        predicted = ("inside the" in line) or ("stable in wall-driven" in line) or \
            ("cavity stable" in line)
        run = subprocess.run([a.bin, "run", path, "--out", os.path.join(out, name), "--quiet"],
                             capture_output=True, text=True)
        speed = peak_speed(os.path.join(out, name, "fields.h5")) / U
        stable = run.returncode == 0 and speed < 1.5
        outcome = "stable" if stable else ("blew up" if run.returncode == 3 else "overshot")
        ok = stable == predicted
        right += ok
        label = op.upper() + (f" + Smagorinsky {cs}" if cs else "")
        print(f"| {n} | {tau} | {label} | {'stable' if predicted else 'likely unstable'} | "
              f"{outcome} | {speed:.2f} | {'yes' if ok else '**no**'} |")
    print(f"\nright for {right} of {len(CASES)}")


if __name__ == "__main__":
    main()
