#!/usr/bin/env python3
"""Write the submerged column-collapse scenes and their dry twins.

For each aspect ratio a in {0.5, 1, 2} and each packing (loose, dense) this writes
  sub-a<A>-<packing>.toml  the column in a viscous liquid (coupled LBM-DEM, PSM),
  dry-a<A>-<packing>.toml  the same grains, settled the same way, collapsing in air (DEM).
The grains are those of the dry DEM study (jobs/column-collapse): disks d = 0.92-1.38 mm,
rho = 2500 kg/m3, friction 0.53, restitution 0.75, rolling resistance 0.3, walls tan 24.8 deg.
Loose: settled with the grains' own friction (2-D solid fraction 0.77 as measured in the runs).
Dense: settled without friction (0.81-0.82 as measured), then run with the same friction.

Usage: make-scenes.py [--out DIR] [--spacing M] [--viscosity M2_S]
"""
import argparse
import math
import os

WIDTH_MM = {0.5: 80, 1: 36, 2: 32}
NAMES = {0.5: "a0.5", 1: "a1", 2: "a2"}
RHO_S, RHO_F = 2500.0, 1000.0


def grains_block(a, L, packing, floor, top):
    H = a * L
    pack_h = H / 0.62
    friction = "" if packing == "loose" else ", friction = 0.0"
    return f'''[grains]
density_kg_m3 = {RHO_S}
gravity_m_s2 = [0.0, -9.81]

[grains.contact]
normal_stiffness_n_m2 = 1.0e6
tangential_stiffness_n_m2 = 0.5e6
restitution = 0.75
friction = 0.53
rolling_friction = 0.3

[grains.time_step]
kind = "critical"
lambda = 0.1

[grains.sample]
kind = "pack"
min_m = [0.0, 0.0]
max_m = [{L:.4f}, {pack_h:.4f}]
sizes = {{ distribution = "uniform", min_radius_m = 0.46e-3, max_radius_m = 0.69e-3 }}
solid_fraction = 0.55
seed = 1
settle = {{ damping_1_s = 20.0, kinetic_energy_per_grain_j_m = 1e-9, max_steps = 600000, trim_above_m = {H - 0.575e-3:.5f}{friction} }}

[[grains.walls]]
name = "floor"
from_m = [0.0, 0.0]
to_m = [{floor:.4f}, 0.0]
friction = 0.46

[[grains.walls]]
name = "back"
from_m = [0.0, 0.0]
to_m = [0.0, {top:.4f}]
friction = 0.46

[[grains.walls]]
name = "gate"
from_m = [{L:.4f}, 0.0]
to_m = [{L:.4f}, {top:.4f}]
friction = 0.46
remove_at_s = 0.0
'''


def geometry(a, L, dx):
    H = a * L
    runout = 1.67 * a  # the dry 2-D DEM law below a = 2.7
    length = L * (1 + 1.25 * runout) + 0.01
    top = max(H / 0.62 * 1.05, H + 0.02)
    nx, ny = math.ceil(length / dx), math.ceil(top / dx)
    return H, nx, ny, nx * dx, ny * dx


def submerged(a, L, packing, dx, nu):
    H, nx, ny, floor, top = geometry(a, L, dx)
    t_c = math.sqrt(H / 9.81)
    # Lattice units: tau from the viscosity and the time step that keeps grains at
    # u_lb = u dt/dx <= 0.05 for u = 0.1 m/s.
    dt = 0.05 * dx / 0.1
    tau = 0.5 + 3 * nu * dt / dx ** 2
    end = 0.1 + 25 * t_c
    return f'''# Submerged granular column collapse, a = H_i/L_i = {a}, {packing} packing
# (Rondon, Pouliquen & Aussillous 2011: loose columns liquefy and run out fast and far,
# dense ones dilate, suck fluid in and creep). Written by make-scenes.py: the grains of the
# dry DEM study (jobs/column-collapse, disks d = 0.92-1.38 mm) in a liquid of
# nu = {nu:g} m2/s, rho = {RHO_F:g} kg/m3, closed tank. PSM coupling at dx = {dx*1e3:g} mm
# ({0.92e-3/dx:.1f}-{1.38e-3/dx:.1f} cells per diameter). The fluid has no gravity of its own:
# the grains feel the reduced gravity (1 - rho/rho_s) g, and the probe pressure is the excess
# pore pressure. Its dry twin is dry-{NAMES[a]}-{packing}.toml.
title = "submerged column collapse a = {a}, {packing}"

[domain]
cells = [{nx}, {ny}]
spacing_m = {dx}

[fluid]
density_kg_m3 = {RHO_F}
viscosity_m2_s = {nu}
reference_velocity_m_s = 0.1
reference_length_m = {H:.4f}
relaxation_time = {tau:.4f}
collision = {{ model = "trt" }}

[boundaries]
west = {{ kind = "wall" }}
east = {{ kind = "wall" }}
south = {{ kind = "wall" }}
north = {{ kind = "wall" }}

{grains_block(a, L, packing, floor, top)}
[coupling]
scheme = "psm"

[run]
end_time_s = {end:.3f}

[output]
every_steps = {max(1, round(end / dt / 10))}
probe_every_steps = {max(1, round(0.005 / dt))}
pictures = true

[[probes]]
kind = "deposit"
name = "deposit"
wall_x_m = 0.0
floor_y_m = 0.0

[[probes]]
kind = "point"
name = "base"
position_m = [{L / 2:.4f}, {dx * 1.5:.6f}]

[[analyses]]
kind = "column-collapse"
wall_x_m = 0.0
floor_y_m = 0.0
deposit = "deposit"
pore_pressure = "base"
'''


def dry(a, L, packing, dx):
    H, nx, ny, floor, top = geometry(a, L, dx)
    t_c = math.sqrt(H / 9.81)
    end = 0.1 + 9 * t_c
    return f'''# Dry twin of sub-{NAMES[a]}-{packing}.toml (same grains, packing and walls), collapsing in
# air: the reference the submerged run-out is compared with. Written by make-scenes.py.
title = "dry column collapse a = {a}, {packing}"

[domain]
size_m = [{floor:.4f}, {top:.4f}]

{grains_block(a, L, packing, floor, top)}
[run]
end_time_s = {end:.3f}
stop_below_kinetic_energy_j_m = 1e-9

[output]
every_s = {end/10:.4f}

[[analyses]]
kind = "column-collapse"
wall_x_m = 0.0
floor_y_m = 0.0
'''


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--out", default=os.path.dirname(os.path.abspath(__file__)))
    p.add_argument("--spacing", type=float, default=2.5e-4)
    p.add_argument("--viscosity", type=float, default=1.0e-5)
    args = p.parse_args()
    for a, mm in WIDTH_MM.items():
        L = mm / 1000
        for packing in ["loose", "dense"]:
            for name, text in [
                (f"sub-{NAMES[a]}-{packing}.toml", submerged(a, L, packing, args.spacing, args.viscosity)),
                (f"dry-{NAMES[a]}-{packing}.toml", dry(a, L, packing, args.spacing)),
            ]:
                with open(os.path.join(args.out, name), "w") as f:
                    f.write(text)


if __name__ == "__main__":
    main()
