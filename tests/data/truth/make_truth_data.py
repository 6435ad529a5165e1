#!/usr/bin/env python3
"""Makes the data of the truth suite (tests/truth/test_truth.c); standard library only.

random-cones.png  40 cones of random radius (7.5-22.5 texels) at random places on a 256x256
                  16-bit height map (white = top): the idea of /work/shared/fixtures/
                  make_random_cones.py at half its size. Not periodic, not symmetric: a technique
                  that mirrors, swaps or shifts an axis shows it here, where the regular
                  procedural maps hide it.
plane-mirrored.obj  the built-in 2x2 plane (y = 0, normal +y) as a 4x4 grid whose u runs right
                  to left (u = (1 - x) / 2): the tangent frame is left-handed.
plane-rotated.obj   the same grid with its UVs rotated 90 degrees (u = (1 - z) / 2,
                  v = (1 - x) / 2): u runs away from the viewer, v to the left.

Run from this folder: python3 make_truth_data.py
"""
import math
import random
import struct
import zlib

SIZE = 256
CONES = 40


def cone_heights():
    rng = random.Random(7)
    cones = [(rng.uniform(0, SIZE), rng.uniform(0, SIZE), rng.uniform(7.5, 22.5))
             for _ in range(CONES)]
    rows = []
    for j in range(SIZE):
        row = []
        for i in range(SIZE):
            h = 0.0
            for cx, cy, r in cones:
                d = math.hypot(i - cx, j - cy) / r
                if d < 1.0:
                    h = max(h, (1.0 - d) ** 1.5)
            row.append(int(round(h * 65535)))
        rows.append(row)
    return rows


def png_chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


def save_grey16(path, rows):
    height, width = len(rows), len(rows[0])
    raw = b"".join(b"\x00" + struct.pack(">%dH" % width, *row) for row in rows)
    header = struct.pack(">IIBBBBB", width, height, 16, 0, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", header) +
                png_chunk(b"IDAT", zlib.compress(raw, 9)) + png_chunk(b"IEND", b""))


def save_grid_obj(path, comment, uv_of):
    cells = 4
    lines = ["# " + comment, "# made by make_truth_data.py"]
    for j in range(cells + 1):
        for i in range(cells + 1):
            x, z = -1.0 + 2.0 * i / cells, -1.0 + 2.0 * j / cells
            lines.append("v %g 0 %g" % (x, z))
    for j in range(cells + 1):
        for i in range(cells + 1):
            x, z = -1.0 + 2.0 * i / cells, -1.0 + 2.0 * j / cells
            lines.append("vt %g %g" % uv_of(x, z))
    lines.append("vn 0 1 0")
    for j in range(cells):
        for i in range(cells):
            a = j * (cells + 1) + i + 1
            b, c, d = a + 1, a + cells + 1, a + cells + 2
            # counter-clockwise seen from +y (z grows toward the viewer)
            for tri in ((a, c, d), (a, d, b)):
                lines.append("f " + " ".join("%d/%d/1" % (k, k) for k in tri))
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    save_grey16("random-cones.png", cone_heights())
    save_grid_obj("plane-mirrored.obj", "2x2 plane, u mirrored: u = (1 - x) / 2, v = (1 - z) / 2",
                  lambda x, z: ((1.0 - x) / 2.0, (1.0 - z) / 2.0))
    save_grid_obj("plane-rotated.obj", "2x2 plane, uvs rotated 90 degrees: u = (1 - z) / 2, "
                  "v = (1 - x) / 2", lambda x, z: ((1.0 - z) / 2.0, (1.0 - x) / 2.0))
