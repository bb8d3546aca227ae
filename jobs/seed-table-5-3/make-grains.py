#!/usr/bin/env python3
"""Write grains.csv: 2500 disks of radius 5 mm on a 50 × 50 grid (12 mm pitch) starting at
(1.2, 1.0) m, each jittered by up to ±0.5 mm (seeded, so the file is reproducible)."""
import random

random.seed(1)
rows = ["x_m, y_m, r_m"]
for j in range(50):
    for i in range(50):
        x = 1.2 + 0.006 + 0.012 * i + random.uniform(-0.0005, 0.0005)
        y = 1.0 + 0.006 + 0.012 * j + random.uniform(-0.0005, 0.0005)
        rows.append(f"{x:.6f}, {y:.6f}, 0.005")
open("grains.csv", "w").write("\n".join(rows) + "\n")
