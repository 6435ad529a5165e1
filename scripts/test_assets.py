#!/usr/bin/env python3
"""Meshes nobody here made, as a test: every OBJ, PLY, glTF and GLB of assimp's test corpus
(Debian's assimp-testmodels, /usr/share/assimp/models) but its invalid/ folder is opened with
`meso info`, and every one that loads is put on a small scene (camera from its bounds, the
procedural bumps, depth 3 % of its radius, no "uv_projection": a mesh without usable texture
coordinates gets the default box projection) and rendered with every technique that can draw
it and with the reference (`meso render --techniques all`).

Checked (docs/techniques.md, "Meshes nobody here made"):
  - no crash and no hang (a timeout), no exit status other than 0 and 2;
  - every refusal is one line, "meso: <file>: <reason>";
  - no technique draws an empty image where the reference draws the object;
  - each technique's coverage IoU and covered PSNR against the reference at or above its floor
    (FLOORS), or the model is listed in KNOWN with its documented reason.
Prints a table of every model and technique and a summary per technique; exits 1 on any
failure.

Usage: scripts/test_assets.py [--meso build/meso] [--models DIR] [--size 64] [--keep DIR]
"""
import argparse
import csv
import math
import os
import re
import subprocess
import sys
import tempfile

EXTENSIONS = (".obj", ".ply", ".gltf", ".glb")
INFO_TIMEOUT_S = 60
RENDER_TIMEOUT_S = 300

# Per technique: (coverage IoU, covered PSNR in dB) floors against the reference at 64 x 64:
# the lowest measured over the models not in KNOWN, minus a margin of 0.05 IoU and 2 dB.
FLOORS = {
    "flat": (0.80, 10.5), "bump": (0.80, 10.5), "horizon": (0.80, 10.5),
    "parallax": (0.80, 11.0), "relief": (0.76, 11.5), "relief_exact": (0.76, 11.5),
    "relief_layers": (0.76, 11.5), "vdm": (0.67, 10.5), "gdm": (0.92, 10.5),
    "tessellation": (0.86, 17.5), "displacement": (0.86, 19.0),
}

# Models under a floor, each with its reason (docs/techniques.md, "Meshes nobody here made").
OPEN_FLAT = ("a flat open surface seen at a grazing angle: its footprint is a thin band and the "
             "reference's open border, where the true surface drops below the mesh's edge, is "
             "as wide as the band")
FOLDS = ("the shell folds on most prisms (3 % of the radius is deeper than the surface's "
         "radius of curvature on thin legs, rods and fins; meso info says so): the truth erodes "
         "those parts and the techniques disagree there")
FACETED = ("per-face normals (every triangle has its own three vertices): displaced along them "
           "the true surface splits open at every edge, which the per-pixel techniques cannot "
           "show")
STACKED = ("stacked coincident copies of each sample (base layer, clear coat, coat only): the "
           "reference's shadow rays from one copy hit the other, so its surfaces are dark")
PER_PIXEL = ("flat", "bump", "horizon", "parallax", "relief", "relief_exact", "relief_layers",
             "vdm")
ALL = PER_PIXEL + ("gdm", "tessellation", "displacement")
KNOWN = {}
for model, techniques, reason in [
        ("OBJ/concave_polygon.obj", PER_PIXEL + ("gdm",), OPEN_FLAT),
        ("OBJ/space_in_material_name.obj", PER_PIXEL + ("gdm",), OPEN_FLAT),
        ("OBJ/regr_3429812.obj", ALL, OPEN_FLAT),
        ("OBJ/spider.obj", ALL, FOLDS),
        ("OBJ/regr01.obj", ALL, FOLDS),
        ("glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb", ALL, FOLDS),
        ("glTF2/draco/2CylinderEngine.gltf", ALL, FOLDS),
        ("PLY/Wuson.ply", ALL, FACETED),
        ("glTF2/ClearCoat-glTF/ClearCoatTest.gltf", ALL, STACKED)]:
    for technique in techniques:
        KNOWN[(model, technique)] = reason


def run(command, timeout):
    """(status, stdout, stderr); status 'timeout' when it did not finish."""
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "timeout", "", ""
    return done.returncode, done.stdout, done.stderr


def refusal_problem(status, stderr):
    """Why a refusal breaks the rules, or None."""
    if status == 0:
        return None
    if status == "timeout":
        return "hang (timeout)"
    if status != 2:
        return "exit status %s" % status
    lines = [line for line in stderr.splitlines() if not line.startswith("meso: warning:")]
    if len(lines) != 1 or not lines[0].startswith("meso: "):
        return "refusal is not one 'meso: ' line: %r" % stderr[-300:]
    return None


def bounds_of(info):
    m = re.search(r"^bounds \(([^)]*)\) \.\. \(([^)]*)\)", info, re.M)
    if not m:
        return None
    lo = [float(x) for x in m.group(1).split(",")]
    hi = [float(x) for x in m.group(2).split(",")]
    return lo, hi


def scene_text(path, lo, hi, size, project, side):
    centre = [(a + b) / 2 for a, b in zip(lo, hi)]
    radius = 0.5 * math.sqrt(sum((b - a) ** 2 for a, b in zip(lo, hi)))
    view = [side * 0.55, side * 0.45, side * 1.0]
    norm = math.sqrt(sum(v * v for v in view))
    # A mesh without usable coordinates gets the box projection with tiles of 0.75 radius
    # (about two across), so that the bumps stay a few pixels wide at 64 x 64; the default
    # tile (a quarter of the largest side) is made for larger images.
    projection = ('"uv_projection": "box", "uv_projection_scale": %.9g,\n    ' % (0.75 * radius)
                  if project else "")
    # 3 radii away the bounding sphere fills a 40-degree field of view with a margin.
    eye = [c + 3.0 * radius * v / norm for c, v in zip(centre, view)]
    fmt = lambda v: "[%s]" % ", ".join("%.9g" % x for x in v)
    return """{
  "image": {"width": %d, "height": %d, "encoding": "linear"},
  "camera": {"eye": %s, "target": %s, "fov_y_deg": 40},
  "lights": [{"type": "directional", "direction": [0.5, 0.8, 0.4]}],
  "objects": [{
    "shape": {"file": "%s"},
    %s"material": {"albedo": [0.8, 0.8, 0.8]},
    "mesostructure": {"height_map": {"procedural": "bumps", "resolution": 64}, "depth": %.9g},
    "technique": "flat"
  }]
}
""" % (size, size, fmt(eye), fmt(centre), path, projection, 0.03 * radius)


def covered_fraction(meso, png):
    """The mean of a coverage mask (meso info prints it): 0 when nothing is drawn."""
    status, info, _ = run([meso, "info", png], INFO_TIMEOUT_S)
    m = re.search(r"^grey .* max ([0-9.]+)", info, re.M)
    return float(m.group(1)) if status == 0 and m else 0.0


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--meso", default=os.path.join(here, "..", "build", "meso"))
    parser.add_argument("--models", default="/usr/share/assimp/models")
    parser.add_argument("--size", type=int, default=64)
    parser.add_argument("--keep", help="write the scenes and images into this folder")
    args = parser.parse_args()
    if not os.path.isdir(args.models):
        print("test-assets: %s not found: install assimp-testmodels (scripts/install-deps.sh)"
              % args.models, file=sys.stderr)
        return 1
    models = []
    for folder, subfolders, files in os.walk(args.models):
        subfolders[:] = sorted(d for d in subfolders if d != "invalid")
        models += [os.path.join(folder, f) for f in sorted(files)
                   if f.lower().endswith(EXTENSIONS)]
    models.sort()
    work = args.keep or tempfile.mkdtemp(prefix="meso-test-assets-")
    os.makedirs(work, exist_ok=True)
    env = dict(os.environ, MESO_CACHE_DIR=os.path.join(work, "cache"))
    os.environ.update(env)

    failures, refused, rows, techniques, behind = [], 0, [], [], set()
    for path in models:
        name = os.path.relpath(path, args.models)
        status, info, err = run([args.meso, "info", path], INFO_TIMEOUT_S)
        problem = refusal_problem(status, err)
        if problem:
            failures.append("%s: meso info: %s" % (name, problem))
            continue
        if status == 2:
            refused += 1
            rows.append((name, "refused: " + err.strip().splitlines()[-1][6:], {}))
            continue
        bounds = bounds_of(info)
        if not bounds:
            failures.append("%s: meso info printed no bounds" % name)
            continue
        slug = re.sub(r"[^A-Za-z0-9]+", "-", name).strip("-")
        project = not re.search(r"^texture coordinates: the file's", info, re.M)
        # Seen from (0.55, 0.45, 1) from its centre; a model that faces away from there
        # (an open mesh seen from behind, which the rasterized techniques cull and the
        # reference does not) is seen from the opposite side.
        for side in (1, -1):
            scene = os.path.join(work, slug + ".json")
            with open(scene, "w") as f:
                f.write(scene_text(path, bounds[0], bounds[1], args.size, project, side))
            out = os.path.join(work, slug)
            status, _, err = run([args.meso, "render", scene, "--techniques", "all", "-o", out,
                                  "--frames", "1"], RENDER_TIMEOUT_S)
            if status != 0 or side == -1:
                break
            flat = os.path.join(out, "flat.coverage.png")
            if not os.path.exists(flat) or covered_fraction(args.meso, flat) > 0:
                break
        problem = refusal_problem(status, err)
        if problem:
            failures.append("%s: meso render: %s" % (name, problem))
            continue
        if status == 2:
            rows.append((name, "render refused: " + err.strip().splitlines()[-1][6:], {}))
            failures.append("%s: loads but its scene is refused: %s" % (name, err.strip()))
            continue
        reference_png = os.path.join(out, "reference.coverage.png")
        if not os.path.exists(reference_png) or covered_fraction(args.meso, reference_png) == 0:
            failures.append("%s: the reference draws nothing" % name)
            continue
        cells = {}
        with open(os.path.join(out, "results.csv")) as f:
            for row in csv.DictReader(f):
                technique = row["technique"]
                if technique == "reference" or row["status"] != "ok":
                    continue
                if technique not in techniques:
                    techniques.append(technique)
                iou, db = float(row["coverage_iou"]), float(row["psnr_covered_db"])
                cells[technique] = (iou, db)
                if covered_fraction(args.meso, os.path.join(out, technique + ".coverage.png")) == 0:
                    failures.append("%s: %s draws an empty image" % (name, technique))
                    continue
                floor = FLOORS.get(technique)
                if floor and (iou < floor[0] or db < floor[1]) and (name, technique) not in KNOWN:
                    failures.append("%s: %s under its floor: IoU %.3f (floor %.2f), covered "
                                    "%.1f dB (floor %.1f)" % (name, technique, iou, floor[0],
                                                             db, floor[1]))
        if side == -1:
            behind.add(name)
        rows.append((name, "", cells))

    # The table: one row a model, IoU / covered dB a technique.
    width = max(len(r[0]) for r in rows) if rows else 10
    print("%-*s  %s" % (width, "model", "  ".join("%-11s" % t[:11] for t in techniques)))
    for name, note, cells in rows:
        if note:
            print("%-*s  %s" % (width, name, note))
            continue
        line = []
        for t in techniques:
            if t in cells:
                mark = "*" if (name, t) in KNOWN else " "
                line.append("%.2f/%4.1f%s " % (cells[t][0], cells[t][1], mark))
            else:
                line.append("%-11s" % "-")
        print("%-*s  %s%s" % (width, name, "  ".join(line),
                              " (seen from behind)" if name in behind else ""))
    rendered = [r for r in rows if not r[1]]
    print("\n%d models: %d refused at load (one line each), %d rendered; * = listed in KNOWN"
          % (len(models), refused, len(rendered)))
    print("%-14s %6s %9s %9s %10s %10s %s" % ("technique", "models", "min IoU", "median",
                                              "min dB", "median", "floor"))
    for t in techniques:
        values = [r[2][t] for r in rendered if t in r[2] and (r[0], t) not in KNOWN]
        if not values:
            continue
        ious = sorted(v[0] for v in values)
        dbs = sorted(v[1] for v in values)
        floor = FLOORS.get(t)
        print("%-14s %6d %9.3f %9.3f %10.1f %10.1f %s" % (
            t, len(values), ious[0], ious[len(ious) // 2], dbs[0], dbs[len(dbs) // 2],
            "%.2f / %.1f dB" % floor if floor else "-"))
    for failure in failures:
        print("test-assets: FAIL: " + failure, file=sys.stderr)
    print("test-assets: %s" % ("%d failures" % len(failures) if failures else "passed"),
          file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
