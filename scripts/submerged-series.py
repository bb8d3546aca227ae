#!/usr/bin/env python3
"""Picture series of the submerged column collapse next to its dry twin.

    scripts/submerged-series.py RUNS A OUT.png     e.g. runs/submerged a2 series-a2.png

Rows: dry loose, submerged loose, dry dense, submerged dense (the runs' own grains_*.png,
coloured by speed). Columns: 0, 20, 40, 60 and 100 % of each run's duration, labelled with the
time in seconds, so the slower submerged collapse shows at equal fractions and equal times can be
read off the labels. Needs Pillow.
"""
import json
import os
import sys

from PIL import Image, ImageDraw

FRACTIONS = [0.0, 0.2, 0.4, 0.6, 1.0]


def frames(run):
    """(time_s, path) of a run's grain pictures, from its simulated time and picture count."""
    pics = sorted(p for p in os.listdir(os.path.join(run, "pictures"))
                  if p.startswith("grains_") and not p.startswith("grains_step"))
    if not pics:  # grains-only runs name pictures by DEM step
        pics = sorted(p for p in os.listdir(os.path.join(run, "pictures")) if p.startswith("grains_step"))
    steps = [int(p.split("_")[-1].split(".")[0]) for p in pics]
    end = json.load(open(os.path.join(run, "summary.json")))["simulated_time_s"]
    return [(end * s / steps[-1], os.path.join(run, "pictures", p)) for s, p in zip(steps, pics)]


def main():
    runs, a, out = sys.argv[1:4]
    rows = [f"{k}-{a}-{p}" for p in ("loose", "dense") for k in ("dry", "sub")]
    width = 300
    tiles = []
    for name in rows:
        fr = frames(os.path.join(runs, name))
        row = []
        for f in FRACTIONS:
            t, path = min(fr, key=lambda x: abs(x[0] - f * fr[-1][0]))
            im = Image.open(path).convert("RGB")
            im = im.resize((width, round(im.height * width / im.width)))
            ImageDraw.Draw(im).text((width - 70, im.height - 60), f"t = {t:.2f} s", fill=(0, 0, 0))
            row.append(im)
        tiles.append((name, row))
    # Bottom-aligned tiles of the shortest picture's height (the domains differ above the column).
    h = min(im.height for _, row in tiles for im in row)
    tiles = [(n, [im.crop((0, im.height - h, width, im.height)) for im in row]) for n, row in tiles]
    label_w = 110
    sheet = Image.new("RGB", (label_w + width * len(FRACTIONS), h * len(rows)), "white")
    draw = ImageDraw.Draw(sheet)
    for i, (name, row) in enumerate(tiles):
        kind, _, packing = name.split("-")
        draw.text((6, i * h + h // 2 - 6), f"{'submerged' if kind == 'sub' else 'dry'} {packing}", fill=(0, 0, 0))
        for j, im in enumerate(row):
            sheet.paste(im, (label_w + j * width, i * h))
    sheet.save(out)


if __name__ == "__main__":
    main()
