#!/usr/bin/env python3
"""Makes the OBJ files of the truth suite (tests/truth/test_truth.c); standard library only.

plane-mirrored.obj  the built-in 2x2 plane (y = 0, normal +y) as a 4x4 grid whose u runs right
                    to left (u = (1 - x) / 2): the tangent frame is left-handed.
plane-rotated.obj   the same grid with its UVs rotated 90 degrees (u = (1 - z) / 2,
                    v = (1 - x) / 2): u runs away from the viewer, v to the left.

random-cones.png, the height map of every truth scene, is ../random-cones/random-cones.png
(40 cones of random radius at random places, 512x512, 16-bit; made by
../random-cones/make_random_cones.py, numpy seed 7) averaged 2x2 down to 256x256:
    convert ../random-cones/random-cones.png -scale 50% -depth 16 -type Grayscale -strip \
        random-cones.png
Not periodic, not symmetric: a technique that mirrors, swaps or shifts an axis shows it here,
where the regular procedural maps hide it.

Run from this folder: python3 make_truth_data.py
"""


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
    save_grid_obj("plane-mirrored.obj", "2x2 plane, u mirrored: u = (1 - x) / 2, v = (1 - z) / 2",
                  lambda x, z: ((1.0 - x) / 2.0, (1.0 - z) / 2.0))
    save_grid_obj("plane-rotated.obj", "2x2 plane, uvs rotated 90 degrees: u = (1 - z) / 2, "
                  "v = (1 - x) / 2", lambda x, z: ((1.0 - z) / 2.0, (1.0 - x) / 2.0))
