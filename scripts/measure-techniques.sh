#!/usr/bin/env bash
# Renders every example and effect-isolation scene with every technique and the reference
# (meso render --techniques all) into OUT (default out/techniques), then prints the tables of
# docs/techniques.md from the results.csv files (scripts/techniques_tables.py).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/techniques}
meso=${MESO:-build/meso}
for scene in examples/bricks-plane.json examples/bumps-sphere.json examples/bricks-teapot.json \
             examples/weave-torus.json examples/effects/occlusion-overhead-light.json \
             examples/effects/shadow-top-view.json; do
    name=$(basename "$scene" .json)
    "$meso" render "$scene" --techniques all -o "$out/$name" --quiet >/dev/null
done
python3 scripts/techniques_tables.py "$out"
