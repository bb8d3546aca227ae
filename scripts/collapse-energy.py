#!/usr/bin/env python3
"""Energy budget of a column-collapse run (MPM or DEM), snapshot by snapshot.

Reads RUN/summary.json and RUN/mpm.h5 or RUN/grains.h5 (`grainflow run ... --out RUN`; set
the scene's [output] every_s small enough to resolve the collapse, e.g. tau_c / 25). Prints,
against t / tau_c (tau_c = sqrt(H_i / g)):
  KE/E0    kinetic energy (DEM: translation and rotation of the disks),
  KEx/E0   its horizontal part,
  dPE/E0   potential energy released since the first snapshot,
  lost/E0  dPE - KE: dissipated (and, in MPM, stored elastically: small here),
  front    the farthest point or disk edge (m),
with E0 the column's initial potential energy above the floor, as in Staron & Hinch (2005).
Needs h5py and numpy.

Usage: scripts/collapse-energy.py RUN [--every N]
"""
import argparse
import json
import math
import os
import sys

import h5py
import numpy as np


def snapshots(f):
    return sorted((k for k in f if k.startswith("step_")), key=lambda k: int(k[5:]))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("run", help="run folder with summary.json and mpm.h5 or grains.h5")
    p.add_argument("--every", type=int, default=1, help="print every N-th snapshot")
    args = p.parse_args()
    s = json.load(open(os.path.join(args.run, "summary.json")))
    scene = s["scene"]
    hi = s["results"].get("collapse.initial_height_m")
    analyses = scene.get("analyses") or []
    if hi is None or not analyses:
        sys.exit("the run has no column-collapse analysis (collapse.initial_height_m)")
    floor = analyses[0]["floor_y_m"]
    if "mpm" in scene:
        mats = scene["mpm"]["materials"]
        if len(mats) != 1:
            sys.exit("MPM runs with one material only (the snapshots do not store the material)")
        rho, g = mats[0]["density_kg_m3"], abs(scene["mpm"]["gravity_m_s2"][1])
        f = h5py.File(os.path.join(args.run, "mpm.h5"), "r")
    else:
        rho, g = scene["grains"]["density_kg_m3"], abs(scene["grains"]["gravity_m_s2"][1])
        f = h5py.File(os.path.join(args.run, "grains.h5"), "r")
    tau_c = math.sqrt(hi / g)
    keys = snapshots(f)
    first = f[keys[0]]
    if "radius" in first:
        # Disks per unit depth: m = rho pi r^2, moment of inertia m r^2 / 2.
        def mass(snap):
            return rho * math.pi * snap["radius"][:] ** 2
        def rot(snap, m):
            return 0.25 * np.sum(m * snap["radius"][:] ** 2 * snap["angular_velocity"][:] ** 2)
        def reach(snap):
            return np.max(snap["position"][:, 0] + snap["radius"][:])
    else:
        # Material points keep their mass: rho times the first snapshot's volume (per unit
        # depth), matched by id since ranks may reorder them.
        m0 = dict(zip(first["id"][:], rho * first["volume"][:, 0]))
        def mass(snap):
            return np.array([m0[i] for i in snap["id"][:]])
        def rot(snap, m):
            return 0.0
        def reach(snap):
            return np.max(snap["position"][:, 0])
    e0 = pe0 = None
    print(f"{'t/tau_c':>8} {'KE/E0':>7} {'KEx/E0':>7} {'dPE/E0':>7} {'lost/E0':>7} {'front':>7}")
    for n, k in enumerate(keys):
        snap = f[k]
        m = mass(snap)
        v = snap["velocity"][:]
        ke = 0.5 * np.sum(m * (v[:, 0] ** 2 + v[:, 1] ** 2)) + rot(snap, m)
        kex = 0.5 * np.sum(m * v[:, 0] ** 2)
        pe = g * np.sum(m * (snap["position"][:, 1] - floor))
        if e0 is None:
            e0 = pe0 = pe
        if n % args.every and n != len(keys) - 1:
            continue
        t = snap.attrs.get("time_s", float("nan"))
        dpe = (pe0 - pe) / e0
        print(f"{t / tau_c:8.2f} {ke / e0:7.4f} {kex / e0:7.4f} {dpe:7.4f} {dpe - ke / e0:7.4f} {reach(snap):7.4f}")


if __name__ == "__main__":
    main()
