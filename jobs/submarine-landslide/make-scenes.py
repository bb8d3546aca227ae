#!/usr/bin/env python3
"""Write the submarine-landslide scenes: a granular mass failing down a submerged slope.

The slope is the floor of the domain with gravity tilted by the slope angle theta,
g = 9.81 (sin theta, -cos theta) m/s2, x pointing downslope. A tilted frame keeps the bed a
straight lattice face (no staircase, the coupling's walls stay exact) and the domain a
rectangle that the slabs split along the run-out; its cost is that the free surface of the
water is not horizontal, which does not matter in a closed, fully submerged tank where the
fluid has no gravity of its own (the grains feel the reduced gravity (1 - rho/rho_s) g and
pressures are excess pore pressures). The bed is rough through Coulomb friction with the
grains (mu_w = 0.46, tan 24.8 deg) and their rolling resistance.

The mass is released by removing the gate at t = 0. Grains are those of the column-collapse
studies (disks d = 0.92-1.38 mm, rho_s = 2500 kg/m3, friction 0.53, rolling 0.3).
Loose: settled with the grains' own friction; dense: settled without friction. Each
submerged scene has a dry twin with the same grains, packing and walls.

Sizes:
  small   a few hundred grains, runs in CI (under a minute);
  medium  about 10 600 grains on 2720 x 610 cells: the validation size (over an hour to
          rest on 2 cores at about 20 MLUPS);
  large   >= 200 000 grains and >= 50 M fluid cells, packed without settling (the packing
          alone would take hours): it must start, run 500 steps on 2 ranks, checkpoint and
          restart; written only with --large.

Usage: make-scenes.py [--out DIR] [--slope DEG] [--large]
"""
import argparse
import math
import os

RHO_S, RHO_F, NU = 2500.0, 1000.0, 1.0e-5
R_MIN, R_MAX = 0.46e-3, 0.69e-3
# Mass length L and height H (m), lattice spacing (m), run-out room (in L) per size.
SIZES = {
    "small": dict(L=0.030, H=0.012, dx=2.5e-4, room=4.0),
    "medium": dict(L=0.170, H=0.090, dx=2.5e-4, room=3.0),
    "large": dict(L=1.350, H=0.340, dx=2.5e-4, room=3.1),
}


def gravity(theta):
    t = math.radians(theta)
    return 9.81 * math.sin(t), -9.81 * math.cos(t)


def geometry(size):
    L, H, dx, room = (SIZES[size][k] for k in ("L", "H", "dx", "room"))
    length = L * (1 + room)
    top = max(H / 0.62 * 1.05, H + 0.01)
    nx, ny = math.ceil(length / dx), math.ceil(top / dx)
    return L, H, dx, nx, ny, nx * dx, ny * dx


def grains_block(size, packing, theta, floor, top):
    L, H = SIZES[size]["L"], SIZES[size]["H"]
    gx, gy = gravity(theta)
    if size == "large":
        # Random addition straight into the column's rectangle: about 0.55 of solid, no
        # settling (hours at this size); the mass compacts as it is released.
        sample = f'''[grains.sample]
kind = "pack"
min_m = [0.0, 0.0]
max_m = [{L:.4f}, {H:.4f}]
sizes = {{ distribution = "uniform", min_radius_m = {R_MIN}, max_radius_m = {R_MAX} }}
solid_fraction = 0.55
seed = 1'''
    else:
        friction = "" if packing == "loose" else ", friction = 0.0"
        sample = f'''[grains.sample]
kind = "pack"
min_m = [0.0, 0.0]
max_m = [{L:.4f}, {H / 0.62:.4f}]
sizes = {{ distribution = "uniform", min_radius_m = {R_MIN}, max_radius_m = {R_MAX} }}
solid_fraction = 0.55
seed = 1
settle = {{ damping_1_s = 20.0, kinetic_energy_per_grain_j_m = 1e-9, max_steps = 2000000, trim_above_m = {H - 0.575e-3:.5f}{friction} }}'''
    return f'''[grains]
density_kg_m3 = {RHO_S}
# The slope: gravity tilted by {theta:g} degrees, x downslope.
gravity_m_s2 = [{gx:.5f}, {gy:.5f}]

[grains.contact]
normal_stiffness_n_m2 = 1.0e6
tangential_stiffness_n_m2 = 0.5e6
restitution = 0.75
friction = 0.53
rolling_friction = 0.3

[grains.time_step]
kind = "critical"
lambda = 0.1

{sample}

[[grains.walls]]
name = "bed"
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


# The grains' and the fluid's kinetic energy over time (not on the large case: each record
# reads the whole 51 M-cell field).
ENERGY = '''[[probes]]
kind = "kinetic-energy"
name = "energy"
'''


# The deposit's run-out and excess pore pressure (not on the large start-up case, which
# stops long before the mass does).
COLLAPSE = '''[[analyses]]
kind = "column-collapse"
wall_x_m = 0.0
floor_y_m = 0.0
deposit = "front"
pore_pressure = "pore"
'''


def end_time(size, theta):
    H = SIZES[size]["H"]
    t_c = math.sqrt(H / 9.81)
    return 0.1 + (30 if size == "small" else 25) * t_c


def collapse_speed(size):
    """The speed scale of the released mass, U = sqrt(g (1 - rho/rho_s) H) (m/s): its front
    runs at about this (Lajeunesse, Monnier & Homsy 2005) and drives the liquid with it, far
    faster than one grain settles. The lattice is set for it: U crosses 0.12 cells per step
    (Ma 0.21). A lattice set for a grain's settling speed (0.1 m/s) put the medium mass's
    front at Ma 0.6 and blew up."""
    return math.sqrt(9.81 * (1 - RHO_F / RHO_S) * SIZES[size]["H"])


def submerged(size, packing, theta):
    L, H, dx, nx, ny, floor, top = geometry(size)
    U = collapse_speed(size)
    dt = 0.12 * dx / U
    tau = 0.5 + 3 * NU * dt / dx ** 2
    end = end_time(size, theta)
    twin = f"dry-{size}-{packing}.toml" if size != "large" else "none (a start-up and scaling case)"
    run = f"end_time_s = {end:.3f}" if size != "large" else "steps = 500"
    every = max(1, round(end / dt / 10)) if size != "large" else 250
    return f'''# Submarine landslide, {size}, {packing} packing, slope {theta:g} deg. Written by
# make-scenes.py (read it for the set-up and its reasons): a {L * 1e3:g} mm x {H * 1e3:g} mm
# granular mass behind a gate on a rough bed, fully submerged in a liquid of
# nu = {NU:g} m2/s, rho = {RHO_F:g} kg/m3 in a closed tank; PSM coupling at dx = {dx * 1e3:g} mm
# ({2 * R_MIN / dx:.1f}-{2 * R_MAX / dx:.1f} cells per diameter). Dry twin: {twin}.
title = "submarine landslide {size}, {packing}, slope {theta:g} deg"

[domain]
cells = [{nx}, {ny}]
spacing_m = {dx}

[fluid]
density_kg_m3 = {RHO_F}
viscosity_m2_s = {NU}
reference_velocity_m_s = {U:.4f}
reference_length_m = {H:.4f}
relaxation_time = {tau:.4f}
collision = {{ model = "trt" }}

[boundaries]
west = {{ kind = "wall" }}
east = {{ kind = "wall" }}
south = {{ kind = "wall" }}
north = {{ kind = "wall" }}

{grains_block(size, packing, theta, floor, top)}
[coupling]
scheme = "psm"

[run]
{run}
precision = "f32"

[output]
every_steps = {every}
probe_every_steps = {max(1, round(0.005 / dt))}
pictures = {"false" if size == "large" else "true"}
checkpoint_at_end = {"true" if size == "large" else "false"}

[[probes]]
kind = "deposit"
name = "front"
wall_x_m = 0.0
floor_y_m = 0.0

[[probes]]
kind = "point"
name = "pore"
position_m = [{L / 2:.4f}, {dx * 1.5:.6f}]

{"" if size == "large" else ENERGY}
{"" if size == "large" else COLLAPSE}'''


# Bed length of the dry twins, in L beyond the gate. In air the mass runs 3-4 times faster
# than under water: on the submerged tank's bed (3-4 L) the medium dry masses and the small
# dense one at 20 deg reached the end wall still flowing, so their run-out was the bed's
# length. A DEM-only run costs nothing per metre of empty bed.
DRY_ROOM = 12.0


def dry(size, packing, theta):
    L, H, dx, nx, ny, _, top = geometry(size)
    floor = L * (1 + DRY_ROOM)
    end = end_time(size, theta)
    return f'''# Dry twin of sub-{size}-{packing}.toml: the same grains, packing, slope and walls, failing
# in air on a bed {DRY_ROOM:g} L long past the gate (the submerged tank's is {SIZES[size]["room"]:g} L);
# the reference the submarine run-out is compared with. Written by make-scenes.py.
title = "dry landslide {size}, {packing}, slope {theta:g} deg"

[domain]
size_m = [{floor:.4f}, {top:.4f}]

{grains_block(size, packing, theta, floor, top)}
# The bed's east end: without it grains that roll off the bed's end fall for ever and their
# kinetic energy grows without bound.
[[grains.walls]]
name = "end"
from_m = [{floor:.4f}, 0.0]
to_m = [{floor:.4f}, {top:.4f}]
friction = 0.46

[run]
end_time_s = {end:.3f}
stop_below_kinetic_energy_j_m = 1e-9

[output]
every_s = {end / 10:.4f}

[[analyses]]
kind = "column-collapse"
wall_x_m = 0.0
floor_y_m = 0.0
'''


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=os.path.dirname(os.path.abspath(__file__)))
    p.add_argument("--slope", type=float, default=15.0, help="slope angle (degrees)")
    p.add_argument("--large", action="store_true", help="also write the large scene")
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    for size in ["small", "medium"] + (["large"] if args.large else []):
        for packing in ["loose", "dense"] if size != "large" else ["loose"]:
            scenes = [(f"sub-{size}-{packing}.toml", submerged(size, packing, args.slope))]
            if size != "large":
                scenes.append((f"dry-{size}-{packing}.toml", dry(size, packing, args.slope)))
            for name, text in scenes:
                with open(os.path.join(args.out, name), "w") as f:
                    f.write(text)


if __name__ == "__main__":
    main()
