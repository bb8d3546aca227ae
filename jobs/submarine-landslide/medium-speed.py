#!/usr/bin/env python3
"""Where the medium submarine landslide's step goes, against the fluid alone.

Packs the medium loose scene's grains once (a 10-step run that writes a checkpoint), then
runs STEPS steps from that checkpoint on 1 rank x 1 thread, 1 rank x 2 threads and 2 ranks
x 1 thread (load balanced), and the same lattice without grains (fluid alone, same
boundaries and operator) on 1 and 2 threads. Prints a markdown table of seconds per step,
MLUPS, grain-steps/s, the stage split and the peak resident memory, and the share of the
fluid cells that are partially saturated (from the grains' final positions), and writes
OUT/speed.md and OUT/speed.csv.

Pictures are off (the canonical scene draws three series); probes and the final snapshot
stay on, as in the canonical run.

Usage: medium-speed.py --out DIR [--steps 400] [--grainflow PATH] [--scene PATH]
"""
import argparse
import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tomllib

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
STAGES = ["collide-stream", "coupling", "dem", "rebalance", "output", "probes"]


def run(cmd, env=None):
    """Run cmd, exit with its output on failure."""
    done = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if done.returncode != 0:
        sys.exit(f"failed ({done.returncode}): {' '.join(cmd)}\n{done.stderr[-3000:]}")


def grainflow_run(gf, scene, out, steps, ranks, threads, restart=None):
    """One run; returns its summary."""
    shutil.rmtree(out, ignore_errors=True)
    cmd = [gf, "run", scene, "--out", out, "--steps", str(steps), "--quiet"]
    cmd += ["--threads", str(threads)]
    if restart:
        cmd += ["--restart", restart]
    env = dict(os.environ)
    if ranks > 1:
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        cmd = ["mpirun", "--oversubscribe", "--bind-to", "none", "-np", str(ranks)] + cmd
    run(cmd, env)
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def fluid_alone(text):
    """The scene's lattice, fluid, boundaries and precision, without grains, probes or
    analyses, writing one snapshot at the end (the runs set their length)."""
    keep, out = True, []
    for line in text.splitlines():
        header = re.match(r"^\s*\[+([^\]]+)\]+", line)
        if header:
            keep = header.group(1).strip() in ("domain", "fluid", "boundaries", "run")
        if keep:
            out.append(line)
    out += ["", "[output]", "every_steps = 1000000", "pictures = false"]
    return "\n".join(out) + "\n"


def partial_share(out, scene):
    """The share of the lattice's cells that a grain overlaps (partially saturated or
    covered), from the grains' last positions in OUT/grains.h5: a cell counts when its
    centre lies within r + √2/2 cells of a grain's centre."""
    dx = scene["domain"]["spacing_m"]
    nx, ny = scene["domain"]["cells"]
    with h5py.File(os.path.join(out, "grains.h5"), "r") as f:
        last = sorted(k for k in f.keys() if k.startswith("step_"))[-1]
        pos, rad = f[last]["position"][:, :2], f[last]["radius"][()]
    covered = np.zeros((ny, nx), dtype=bool)
    reach = rad / dx + math.sqrt(0.5)
    for (x, y), r in zip(pos / dx, reach):
        x0, x1 = max(int(x - r), 0), min(int(x + r) + 1, nx)
        y0, y1 = max(int(y - r), 0), min(int(y + r) + 1, ny)
        if x0 >= x1 or y0 >= y1:
            continue
        cx = np.arange(x0, x1) + 0.5
        cy = np.arange(y0, y1)[:, None] + 0.5
        covered[y0:y1, x0:x1] |= (cx - x) ** 2 + (cy - y) ** 2 <= r * r
    return covered.mean()


def row(name, s, steps, grains):
    """A table row from summary s of a run of `steps` steps."""
    st = s["stage_seconds"]
    loop = sum(st.values())
    r = {
        "run": name,
        "s_per_step": loop / steps,
        "mlups": s["mlups"],
        "grain_steps_per_s": grains * steps / loop if grains else 0.0,
        "peak_mib": s["peak_memory_bytes"] / 2**20,
    }
    for k in STAGES:
        r[k] = st.get(k, 0.0) / loop
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--grainflow", default=os.path.join(ROOT, "target/release/grainflow"))
    ap.add_argument("--scene", default=os.path.join(HERE, "sub-medium-loose.toml"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    with open(a.scene) as f:
        text = f.read()
    scene = tomllib.loads(text)
    coupled = os.path.join(a.out, "coupled.toml")
    with open(coupled, "w") as f:
        f.write(text.replace("pictures = true", "pictures = false").replace(
            "checkpoint_at_end = false", "checkpoint_at_end = true"))
    fluid = os.path.join(a.out, "fluid.toml")
    with open(fluid, "w") as f:
        f.write(fluid_alone(text))
    print("packing the grains (a 10-step run) ...", file=sys.stderr)
    start = os.path.join(a.out, "start")
    grainflow_run(a.grainflow, coupled, start, 10, 1, 2)
    ck = os.path.join(start, "checkpoint.h5")
    with h5py.File(os.path.join(start, "grains.h5"), "r") as f:
        last = sorted(k for k in f.keys() if k.startswith("step_"))[-1]
        grains = len(f[last]["radius"])
    rows = []
    for ranks, threads in [(1, 1), (1, 2), (2, 1)]:
        name = f"coupled, {ranks} rank(s) x {threads} thread(s)"
        print(name, "...", file=sys.stderr)
        out = os.path.join(a.out, f"coupled-{ranks}x{threads}")
        s = grainflow_run(a.grainflow, coupled, out, 10 + a.steps, ranks, threads, ck)
        rows.append(row(name, s, a.steps, grains))
        last_out = out
    for threads in [1, 2]:
        name = f"fluid alone, 1 rank x {threads} thread(s)"
        print(name, "...", file=sys.stderr)
        out = os.path.join(a.out, f"fluid-1x{threads}")
        rows.append(row(name, grainflow_run(a.grainflow, fluid, out, a.steps, 1, threads),
                        a.steps, 0))
    share = partial_share(last_out, scene)
    cols = ["run", "s_per_step", "mlups", "grain_steps_per_s", *STAGES, "peak_mib"]
    with open(os.path.join(a.out, "speed.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols)
        w.writeheader()
        w.writerows(rows)
    nx, ny = scene["domain"]["cells"]
    lines = [
        f"{nx} x {ny} cells, {grains} grains, {a.steps} steps from a checkpoint at step 10;"
        f" grains overlap {100 * share:.1f} % of the cells at the end",
        "",
        "| run | s / step | MLUPS | M grain-steps/s | fluid | coupling | DEM | rebalance"
        " | output | probes | peak MiB |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        gs = f"{r['grain_steps_per_s'] / 1e6:.2f}" if r["grain_steps_per_s"] else ""
        parts = " | ".join(f"{100 * r[k]:.0f} %" for k in STAGES)
        lines.append(f"| {r['run']} | {r['s_per_step']:.4f} | {r['mlups']:.0f} | {gs} | "
                     f"{parts} | {r['peak_mib']:.0f} |")
    text = "\n".join(lines) + "\n"
    with open(os.path.join(a.out, "speed.md"), "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()
