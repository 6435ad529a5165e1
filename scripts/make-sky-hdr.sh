#!/usr/bin/env bash
# Make examples/sky.hdr: the procedural sky of docs/scene-format.md ("environment": {"sky": {}})
# at 128 x 64 texels with its default sun, written as a Radiance .hdr by meso itself
# (scripts/make_sky_hdr.c). Usage: scripts/make-sky-hdr.sh [BUILD_DIR]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
cmake --build "$build" --target make_sky_hdr >/dev/null
"$build/make_sky_hdr" "$root/examples/sky.hdr" 128
echo "wrote $root/examples/sky.hdr"
