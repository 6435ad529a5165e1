#!/usr/bin/python3
"""Where a technique's error lies: RMSE and PSNR against the reference by distance from the
reference's outline and by lit / shadowed, on linear images (meso render --linear).

usage: error_bands.py REFERENCE.png REFERENCE.coverage.png SHADOW_MASK.png TECHNIQUE.png [...]

Each TECHNIQUE.png needs its TECHNIQUE.coverage.png beside it (meso render --coverage): the
error is taken over the pixels both cover, as meso compare's covered PSNR, and the pixels only
one of the two covers are counted per band.

SHADOW_MASK is the reference rendered with "ambient": [0, 0, 0]: a covered pixel that is black
there sees no light (cast or attached shadow). Needs python3-numpy and python3-pil (installed
by scripts/install-deps.sh). Prints one Markdown table."""
import sys

import numpy as np
from PIL import Image


def load(path):
    a = np.asarray(Image.open(path)).astype(np.float64)
    a /= 65535.0 if a.max() > 255 else 255.0
    return a if a.ndim == 2 else a[..., :3]


def distance_to_outline(mask):
    """City-block distance (pixels) of every covered pixel to the nearest uncovered one."""
    inside = mask > 0.5
    big = mask.shape[0] + mask.shape[1]
    dist = np.where(inside, big, 0).astype(np.int64)
    for _ in range(2):  # forward then backward sweeps, rows and columns
        for axis in (0, 1):
            d = np.moveaxis(dist, axis, 0)
            for i in range(1, d.shape[0]):
                d[i] = np.minimum(d[i], d[i - 1] + 1)
            for i in range(d.shape[0] - 2, -1, -1):
                d[i] = np.minimum(d[i], d[i + 1] + 1)
    return dist


def psnr(err2):
    return float("inf") if err2 == 0 else -10.0 * np.log10(err2)


def main():
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    ref, cov, lit_only = load(sys.argv[1]), load(sys.argv[2]), load(sys.argv[3])
    covered = cov > 0.5
    dist = distance_to_outline(cov)
    shadowed = covered & (lit_only.max(axis=2) < 1e-3)
    bands = [("outline 0-2 px", (dist >= 1) & (dist <= 2)), ("2-5 px", (dist > 2) & (dist <= 5)),
             ("5-10 px", (dist > 5) & (dist <= 10)), ("over 10 px", dist > 10),
             ("lit", covered & ~shadowed), ("shadowed", shadowed), ("all covered", covered)]
    names = sys.argv[4:]
    images = [load(n) for n in names]
    masks = [load(n[:-4] + ".coverage.png") > 0.5 for n in names]
    print("| band | pixels | " + " | ".join(
        f"{n.split('/')[-1][:-4]}: dB (share of error), coverage misses" for n in names) + " |")
    print("| --- | ---: |" + " ---: |" * len(names))
    errors = [((img - ref) ** 2).mean(axis=2) for img in images]
    totals = [e[covered & m].sum() for e, m in zip(errors, masks)]
    for label, band in bands:
        cells = []
        for e, m, total in zip(errors, masks, totals):
            both = band & m
            cells.append(f"{psnr(e[both].mean()):.1f} ({100 * e[both].sum() / total:.0f} %), "
                         f"{int((band & ~m).sum())}")
        print(f"| {label} | {int(band.sum())} | " + " | ".join(cells) + " |")

main()
