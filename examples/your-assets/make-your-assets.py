#!/usr/bin/python3
"""Makes the stand-in assets of docs/your-assets.md, standard library only:

my-height-8bit.png   a tileable cobblestone height map, 128 x 128, 8-bit grey (white = high)
my-height-16bit.png  the same heights, 16-bit grey
my-height-rgb.png    the same heights as an RGB picture (meso reads its luminance)
my-mesh.obj          a dome-shaped patch, 16 x 16 quads, with normals and UVs in [0, 1]
my-mesh.gltf         the same patch as glTF 2.0 (one embedded buffer; glTF's v runs down)
my-tile.obj          one closed tile of a solid: a rounded stud in the unit box (z = 1 on the mesh)

Run from this folder: python3 make-your-assets.py
"""
import base64
import math
import random
import struct
import zlib

SIZE = 128


def write_png(path, width, height, channels, bits, rows):
    """rows: a list of lists of ints, channels values a pixel, each < 2**bits."""
    colour_type = {1: 0, 3: 2}[channels]
    raw = bytearray()
    for row in rows:
        raw.append(0)
        for value in row:
            raw += struct.pack(">H", value) if bits == 16 else bytes([value])

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    header = struct.pack(">IIBBBBB", width, height, bits, colour_type, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) +
                chunk(b"IDAT", zlib.compress(bytes(raw), 9)) + chunk(b"IEND", b""))


def cobble_heights():
    """Cobblestones: a jittered 4 x 4 grid of stones, each a rounded dome, periodic in u and v."""
    rng = random.Random(5)
    cells = 4
    centres = [((i + 0.5 + rng.uniform(-0.2, 0.2)) / cells, (j + 0.5 + rng.uniform(-0.2, 0.2)) / cells)
               for j in range(cells) for i in range(cells)]
    heights = []
    for y in range(SIZE):
        row = []
        for x in range(SIZE):
            u, v = (x + 0.5) / SIZE, (y + 0.5) / SIZE
            dists = []
            for cu, cv in centres:
                du = (u - cu + 0.5) % 1.0 - 0.5
                dv = (v - cv + 0.5) % 1.0 - 0.5
                dists.append(math.hypot(du, dv))
            dists.sort()
            edge = dists[1] - dists[0]          # distance to the border between two stones
            h = min(1.0, edge * cells * 2.2)    # 0 in the joints, 1 on the stones' tops
            row.append(math.sqrt(h))            # rounded shoulders
        heights.append(row)
    return heights


def write_height_maps():
    h = cobble_heights()
    write_png("my-height-8bit.png", SIZE, SIZE, 1, 8, [[round(v * 255) for v in r] for r in h])
    write_png("my-height-16bit.png", SIZE, SIZE, 1, 16, [[round(v * 65535) for v in r] for r in h])
    rgb = []
    for r in h:
        row = []
        for v in r:   # a warm grey whose luminance is about v
            row += [min(255, round(v * 255 * 1.08)), round(v * 255 * 0.99), round(v * 255 * 0.86)]
        rgb.append(row)
    write_png("my-height-rgb.png", SIZE, SIZE, 3, 8, rgb)


def dome_patch(n=16):
    """Vertices (position, normal, uv) and triangles of y = 0.3 cos(pi x / 2) cos(pi z / 2)."""
    verts, tris = [], []
    for j in range(n + 1):
        for i in range(n + 1):
            x, z = -1 + 2 * i / n, -1 + 2 * j / n
            y = 0.3 * math.cos(math.pi * x / 2) * math.cos(math.pi * z / 2)
            dydx = -0.3 * math.pi / 2 * math.sin(math.pi * x / 2) * math.cos(math.pi * z / 2)
            dydz = -0.3 * math.pi / 2 * math.cos(math.pi * x / 2) * math.sin(math.pi * z / 2)
            nx, ny, nz = -dydx, 1.0, -dydz
            length = math.sqrt(nx * nx + ny * ny + nz * nz)
            # u along +x, v along -z: seen from above with -z up, the map reads like its file
            verts.append(((x, y, z), (nx / length, ny / length, nz / length), (i / n, 1 - j / n)))
    for j in range(n):
        for i in range(n):
            a, b = j * (n + 1) + i, j * (n + 1) + i + 1
            c, d = a + n + 1, b + n + 1
            tris += [(a, c, b), (b, c, d)]     # counter-clockwise seen from +y
    return verts, tris


def write_obj(path, comment, verts, tris, with_uv=True, with_normals=True):
    lines = ["# " + comment, "# made by make-your-assets.py"]
    lines += ["v %.6f %.6f %.6f" % p for p, _, _ in verts]
    if with_normals:
        lines += ["vn %.6f %.6f %.6f" % n for _, n, _ in verts]
    if with_uv:
        lines += ["vt %.6f %.6f" % t for _, _, t in verts]
    for a, b, c in tris:
        if with_uv and with_normals:
            lines.append("f %d/%d/%d %d/%d/%d %d/%d/%d" % (a + 1, a + 1, a + 1, b + 1, b + 1, b + 1,
                                                          c + 1, c + 1, c + 1))
        else:
            lines.append("f %d %d %d" % (a + 1, b + 1, c + 1))
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def write_gltf(path, verts, tris):
    positions = b"".join(struct.pack("<3f", *p) for p, _, _ in verts)
    normals = b"".join(struct.pack("<3f", *n) for _, n, _ in verts)
    uvs = b"".join(struct.pack("<2f", t[0], 1 - t[1]) for _, _, t in verts)  # glTF: v down
    indices = b"".join(struct.pack("<3H", *t) for t in tris)
    data = positions + normals + uvs + indices
    views, offset = [], 0
    for block, target in ((positions, 34962), (normals, 34962), (uvs, 34962), (indices, 34963)):
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(block), "target": target})
        offset += len(block)
    xs = [p[0] for p, _, _ in verts]
    ys = [p[1] for p, _, _ in verts]
    zs = [p[2] for p, _, _ in verts]
    doc = {
        "asset": {"version": "2.0", "generator": "make-your-assets.py"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "name": "dome"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                    "indices": 3}]}],
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
        "bufferViews": views,
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(verts), "type": "VEC3",
             "min": [min(xs), min(ys), min(zs)], "max": [max(xs), max(ys), max(zs)]},
            {"bufferView": 1, "componentType": 5126, "count": len(verts), "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": len(verts), "type": "VEC2"},
            {"bufferView": 3, "componentType": 5123, "count": 3 * len(tris), "type": "SCALAR"},
        ],
    }
    import json
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def stud_tile(sides=16, rings=6):
    """A closed stud: a cylinder of radius 0.28 from z = 0.05 up to a rounded cap that ends at
    z = 0.95, centred in the tile. Tile conventions: x, y -> u, v; z -> 1 - w (z = 1 on the mesh)."""
    verts, tris = [], []
    cx = cy = 0.5
    radius, z_low, z_top, cap = 0.28, 0.05, 0.95, 0.12
    profile = [(radius, z_low)]   # (radius, z) from the bottom edge up over the cap
    for k in range(rings + 1):
        a = k / rings * math.pi / 2
        profile.append((radius * math.cos(a), z_top - cap + cap * math.sin(a)))
    for r, z in profile[:-1]:
        for s in range(sides):
            a = 2 * math.pi * s / sides
            verts.append((cx + r * math.cos(a), cy + r * math.sin(a), z))
    top = len(verts)
    verts.append((cx, cy, z_top))
    bottom = len(verts)
    verts.append((cx, cy, z_low))
    ring_count = len(profile) - 1
    for k in range(ring_count - 1):
        for s in range(sides):
            a, b = k * sides + s, k * sides + (s + 1) % sides
            c, d = a + sides, b + sides
            tris += [(a, b, d), (a, d, c)]     # outward
    last = (ring_count - 1) * sides
    for s in range(sides):
        tris.append((last + s, last + (s + 1) % sides, top))
        tris.append((bottom, (s + 1) % sides, s))
    return [(v, None, None) for v in verts], tris


def main():
    write_height_maps()
    verts, tris = dome_patch()
    write_obj("my-mesh.obj", "a dome-shaped patch with UVs (docs/your-assets.md)", verts, tris)
    write_gltf("my-mesh.gltf", verts, tris)
    verts, tris = stud_tile()
    write_obj("my-tile.obj", "one closed tile of a solid: a rounded stud (docs/your-assets.md)",
              verts, tris, with_uv=False, with_normals=False)


if __name__ == "__main__":
    main()
