#!/usr/bin/env python3
"""Writes examples/assets/chainmail-tile.obj: one tile of chain mail as a closed mesh in the
unit box (docs/design.md's tile conventions: x, y -> u, v, periodic; z -> 1 - w, z = 1 on the mesh).
Two rings of radius 0.4 tilted 60 degrees in opposite senses about x, one at the tile's
centre, one at its corner, so neighbouring rings overlap as in chain mail without touching
(their centre lines stay 0.176 apart, more than two tube radii of 0.07). The corner ring (it
crosses the tile's border; meso continues it in the neighbouring tiles). Deterministic."""
import math, sys

def torus(cx, cy, cz, tilt_deg, major, minor, n_major=48, n_minor=16):
    t = math.radians(tilt_deg)
    verts, faces = [], []
    for i in range(n_major):
        a = 2 * math.pi * i / n_major
        for j in range(n_minor):
            b = 2 * math.pi * j / n_minor
            x = (major + minor * math.cos(b)) * math.cos(a)
            y = (major + minor * math.cos(b)) * math.sin(a)
            z = minor * math.sin(b)
            # tilt about the x axis
            y, z = y * math.cos(t) - z * math.sin(t), y * math.sin(t) + z * math.cos(t)
            verts.append((cx + x, cy + y, cz + z))
    for i in range(n_major):
        for j in range(n_minor):
            a = i * n_minor + j
            b = ((i + 1) % n_major) * n_minor + j
            c = ((i + 1) % n_major) * n_minor + (j + 1) % n_minor
            d = i * n_minor + (j + 1) % n_minor
            faces += [(a, b, c), (a, c, d)]  # outward: counter-clockwise seen from outside
    return verts, faces

def main(path):
    out = ["# chain mail tile for meso (scripts/make-chainmail-tile.py): closed, unit box"]
    base = 0
    for ring in (torus(0.5, 0.5, 0.53, 60.0, 0.4, 0.07), torus(0.0, 0.0, 0.53, -60.0, 0.4, 0.07)):
        verts, faces = ring
        out += ["v %.6f %.6f %.6f" % v for v in verts]
        out += ["f %d %d %d" % (base + a + 1, base + b + 1, base + c + 1) for a, b, c in faces]
        base += len(verts)
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")

main(sys.argv[1] if len(sys.argv) > 1 else "examples/assets/chainmail-tile.obj")
