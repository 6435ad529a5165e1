#!/usr/bin/python3
"""One error-vs-time plot across several scenes, as SVG (docs/choosing.md).

    scripts/error-vs-time-all.py DIR OUT.svg

DIR holds one folder per scene as `meso render A.json B.json ... --techniques all -o DIR`
writes them, each with its results.json. Every technique of every scene is one point: x the
median frame time (log scale), y the PSNR over the pixels both images cover against the
reference, one colour a technique. Standard library only.
"""
import json
import math
import os
import sys
from xml.sax.saxutils import escape

COLOURS = {
    "flat": "#969696", "bump": "#8c564b", "horizon": "#bcbd22", "parallax": "#e377c2",
    "relief": "#1f77b4", "relief_exact": "#17becf", "relief_layers": "#2ca02c",
    "vdm": "#ff7f0e", "gdm": "#d62728", "tessellation": "#9467bd", "displacement": "#000000",
}
WIDTH, HEIGHT = 900, 560
LEFT, RIGHT, TOP, BOTTOM = 70, 170, 50, 60


def load(folder):
    points = []
    for scene in sorted(os.listdir(folder)):
        path = os.path.join(folder, scene, "results.json")
        if not os.path.exists(path):
            continue
        with open(path, encoding="utf-8") as f:
            runs = json.load(f)["runs"]
        for run in runs:
            if run.get("rendered") and "psnr_covered_db" in run and run["frame_ms"] > 0:
                points.append((scene, run["technique"], run["frame_ms"], run["psnr_covered_db"]))
    return points


def plot(points, title):
    t_lo = math.floor(math.log10(min(p[2] for p in points)))
    t_hi = math.ceil(math.log10(max(p[2] for p in points)))
    db_lo = 5 * math.floor(min(p[3] for p in points) / 5)
    db_hi = 5 * math.ceil(max(p[3] for p in points) / 5)
    w, h = WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM

    def x_of(ms):
        return LEFT + (math.log10(ms) - t_lo) / max(t_hi - t_lo, 1) * w

    def y_of(db):
        return TOP + (db_hi - db) / max(db_hi - db_lo, 5) * h

    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" '
           'font-family="sans-serif" font-size="12">' % (WIDTH, HEIGHT),
           '<rect width="100%" height="100%" fill="white"/>',
           '<text x="%d" y="24" font-size="15">%s</text>' % (LEFT, escape(title))]
    for d in range(t_lo, t_hi + 1):
        x = x_of(10.0 ** d)
        out.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#e6e6e6"/>' % (x, TOP, x, TOP + h))
        out.append('<text x="%.1f" y="%d" text-anchor="middle">%g</text>' % (x, TOP + h + 18, 10.0 ** d))
    for db in range(db_lo, db_hi + 1, 5):
        y = y_of(db)
        out.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#e6e6e6"/>' % (LEFT, y, LEFT + w, y))
        out.append('<text x="%d" y="%.1f" text-anchor="end">%d</text>' % (LEFT - 6, y + 4, db))
    out.append('<rect x="%d" y="%d" width="%d" height="%d" fill="none" stroke="black"/>' % (LEFT, TOP, w, h))
    out.append('<text x="%d" y="%d" text-anchor="middle">median frame time, ms (log scale)</text>'
               % (LEFT + w // 2, HEIGHT - 16))
    out.append('<text x="%d" y="%d">PSNR over covered pixels, dB</text>' % (8, TOP - 8))
    for scene, technique, ms, db in points:
        out.append('<circle cx="%.1f" cy="%.1f" r="4.5" fill="%s" fill-opacity="0.85">'
                   '<title>%s, %s: %.2f ms, %.2f dB</title></circle>'
                   % (x_of(ms), y_of(db), COLOURS.get(technique, "#646464"), escape(scene),
                      escape(technique), ms, db))
    seen = [t for t in COLOURS if any(p[1] == t for p in points)]
    for i, technique in enumerate(seen):
        y = TOP + 12 + 20 * i
        x = LEFT + w + 20
        out.append('<circle cx="%d" cy="%d" r="5" fill="%s"/>' % (x, y, COLOURS[technique]))
        out.append('<text x="%d" y="%d">%s</text>' % (x + 12, y + 4, technique))
    out.append("</svg>\n")
    return "\n".join(out)


def main():
    if len(sys.argv) != 3:
        print("usage: scripts/error-vs-time-all.py DIR OUT.svg", file=sys.stderr)
        return 2
    points = load(sys.argv[1])
    if not points:
        print("error-vs-time-all.py: %s: no results.json below it" % sys.argv[1], file=sys.stderr)
        return 2
    title = "%d examples: covered PSNR against the reference vs median frame time" % len(
        {p[0] for p in points})
    tmp = sys.argv[2] + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(plot(points, title))
    os.replace(tmp, sys.argv[2])
    return 0


if __name__ == "__main__":
    sys.exit(main())
