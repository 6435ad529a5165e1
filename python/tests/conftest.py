"""Shared helpers of the Python package's tests (run by `make test` through ctest, which sets
PYTHONPATH to the built package and MESO_PROGRAM to the `meso` program)."""

import os
import struct
import subprocess
import zlib

import numpy as np
import pytest

PROGRAM = os.environ.get("MESO_PROGRAM", os.path.join(os.path.dirname(__file__), "..", "..",
                                                      "build", "meso"))


def write_png(path, array):
    """A PNG of a uint8 or uint16 array (height, width) grey or (height, width, 3) RGB,
    written here so that the test does not depend on meso's own writer."""
    array = np.asarray(array)
    bits = 16 if array.dtype == np.uint16 else 8
    colour_type = 2 if array.ndim == 3 else 0
    height, width = array.shape[:2]
    rows = array.astype(">u2" if bits == 16 else "u1").reshape(height, -1)
    raw = b"".join(b"\0" + row.tobytes() for row in rows)

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    header = struct.pack(">IIBBBBB", width, height, bits, colour_type, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) +
                chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def run_program(*args, cwd=None):
    """(exit status, stdout, stderr) of the meso program."""
    done = subprocess.run([PROGRAM, *map(str, args)], capture_output=True, text=True, cwd=cwd)
    return done.returncode, done.stdout, done.stderr


def asymmetric_heights(height=48, width=64, seed=7):
    """A map that is not symmetric in u, v or under rotation: cones of random radii at random
    places over a ramp, as uint16 (so that a 16-bit PNG holds it exactly)."""
    rng = np.random.default_rng(seed)
    v, u = np.mgrid[0:height, 0:width]
    h = 0.25 + 0.5 * u / width * (0.6 + 0.4 * v / height)
    for _ in range(7):
        cu, cv, r = rng.uniform(0, width), rng.uniform(0, height), rng.uniform(4, 14)
        d = np.hypot(u - cu, v - cv)
        h = np.maximum(h, 1.0 - d / r * 0.8)
    return np.round(np.clip(h, 0, 1) * 65535).astype(np.uint16)


def plane_scene(height_map, technique="relief", **extra):
    """A plane of the height map seen at an angle, lit from one side."""
    mesostructure = {"height_map": height_map, "depth": 0.1}
    mesostructure.update(extra.pop("mesostructure", {}))
    scene = {
        "image": {"width": 96, "height": 72, "background": [0.02, 0.02, 0.03]},
        "camera": {"eye": [0.4, 1.6, 2.0], "target": [0.05, 0.0, 0.1], "up": [0, 1, 0],
                   "fov_y_deg": 40},
        "lights": [{"type": "directional", "direction": [-0.7, 0.6, -0.3]}],
        "objects": [{"shape": "plane", "size": 2, "uv_scale": [2, 1.5],
                     "material": {"albedo": [0.9, 0.8, 0.7]},
                     "mesostructure": mesostructure, "technique": technique}],
    }
    scene["objects"][0].update(extra)
    return scene


@pytest.fixture
def cones():
    return asymmetric_heights()
