#!/usr/bin/env bash
# The relief-impostor figure of docs/techniques/relief_layers.md (Policarpo & Oliveira 2006
# Fig. 11 in spirit): examples/teapot-impostor.json from several views, each beside the
# reference (ray-traced) image of the real teapot. Usage: scripts/teapot-impostor-figure.sh [OUT.png]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/images/relief_layers-teapot-impostor.png}
tmp=$(mktemp -d)
views=("2.2 2.6 3.6" "-3.6 0.9 1.2" "0.4 4.2 0.6" "1.6 -2.6 3.0")
i=0
for eye in "${views[@]}"; do
    python3 - "$eye" "$tmp/impostor-$i.json" "$tmp/real-$i.json" <<'PY'
import json, sys
eye = [float(x) for x in sys.argv[1].split()]
scene = json.load(open("examples/teapot-impostor.json"))
scene["image"]["width"] = scene["image"]["height"] = 256
scene["camera"]["eye"] = eye
json.dump(scene, open(sys.argv[2], "w"))
obj = scene["objects"][0]
real = {"name": "teapot", "shape": "teapot", "material": obj["material"], "technique": "reference"}
scene["objects"] = [real]
json.dump(scene, open(sys.argv[3], "w"))
PY
    build/meso render "$tmp/impostor-$i.json" -o "$tmp/impostor-$i.png" --quiet
    build/meso render "$tmp/real-$i.json" -o "$tmp/real-$i.png" --quiet
    i=$((i + 1))
done
convert "$tmp"/impostor-{0,1,2,3}.png +append "$tmp/top.png"
convert "$tmp"/real-{0,1,2,3}.png +append "$tmp/bottom.png"
convert "$tmp/top.png" "$tmp/bottom.png" -append "$out"
for k in 0 1 2 3; do build/meso compare "$tmp/impostor-$k.png" "$tmp/real-$k.png" 2>&1 | grep -i psnr | head -1 || true; done
rm -rf "$tmp"
echo "wrote $out (top: relief_layers on one quad; bottom: reference of the real teapot)"
