#!/usr/bin/env bash
# The paper's Table 1 layout (Policarpo & Oliveira 2006: plane / sphere / teapot x lighting
# only / self-shadows / silhouettes / both, multilayer (ML) and height-field (HF) maps) with
# meso's relief_layers: median ms a frame at 512x512 on --threads (default 2) from `meso bench`.
# ML = the weave solid (4 layers), HF = the bricks height field (1 layer). Prints a Markdown
# table and the load average (the figures mean little on a loaded machine).
# Usage: scripts/measure-relief-layers-table.sh [THREADS] [FRAMES]
set -euo pipefail
cd "$(dirname "$0")/.."
threads=${1:-2}
frames=${2:-10}
tmp=$(mktemp -d)
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
python3 - "$tmp" <<'PY'
import json, sys
tmp = sys.argv[1]
shapes = {
    "plane": ({"shape": "plane", "size": 2, "uv_scale": [3, 3]},
              {"eye": [0, 1.9, 2.3], "target": [0, -0.05, 0.1]}),
    "sphere": ({"shape": "sphere", "size": 1, "uv_scale": [6, 3]},
               {"eye": [0, 1.5, 4.3], "target": [0, 0, 0]}),
    "teapot": ({"shape": "teapot", "uv_scale": [4, 4]},
               {"eye": [0, 1.9, 3.6], "target": [0, 0.1, 0]}),
}
maps = {
    "ML": {"solid": {"procedural": "weave"}, "depth": 0.08},
    "HF": {"height_map": {"procedural": "bricks", "resolution": 512}, "depth": 0.06},
}
configs = {"lighting": (0, 0), "shadows": (1, 0), "silhouettes": (0, 1), "both": (1, 1)}
for shape, (obj, cam) in shapes.items():
    for m, meso in maps.items():
        for c, (sh, si) in configs.items():
            o = dict(obj)
            o.update({"material": {"albedo": [0.8, 0.7, 0.5]}, "mesostructure": meso,
                      "technique": "relief_layers",
                      "technique_options": {"shadows": sh, "silhouettes": si}})
            scene = {"image": {"width": 512, "height": 512},
                     "camera": dict(cam, up=[0, 1, 0], fov_y_deg=40),
                     "ambient": [0.1, 0.1, 0.1],
                     "lights": [{"type": "directional", "direction": [-0.5, 0.8, 0.4],
                                 "color": [1, 1, 1]}],
                     "objects": [o]}
            json.dump(scene, open(f"{tmp}/{shape}-{m}-{c}.json", "w"))
PY
build/meso bench "$tmp"/*.json --techniques relief_layers --threads "$threads" --frames "$frames" \
    --json "$tmp/bench.json" --quiet > /dev/null
python3 - "$tmp/bench.json" <<'PY'
import json, sys, os
data = json.load(open(sys.argv[1]))
runs = data.get("runs", data if isinstance(data, list) else [])
ms = {}
for r in runs:
    name = os.path.basename(r.get("scene", "")).replace(".json", "")
    ms[name] = r.get("ms") or r.get("median_ms") or r.get("frame_ms")
print("| shape | map | lighting | self-shadows | silhouettes | both |")
print("| --- | --- | --- | --- | --- | --- |")
for shape in ("plane", "sphere", "teapot"):
    for m in ("ML", "HF"):
        cells = []
        for c in ("lighting", "shadows", "silhouettes", "both"):
            v = ms.get(f"{shape}-{m}-{c}")
            cells.append(f"{v:.1f} ms ({1000.0 / v:.0f} fps)" if v else "-")
        print(f"| {shape} | {m} | " + " | ".join(cells) + " |")
PY
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
rm -rf "$tmp"
