#!/usr/bin/env bash
# The RTV's size and RMSE table of docs/techniques/gdm-gi.md: bakes the RTV of bark-cylinder's
# and weave-teapot's mesostructure (scripts/measure_rtv.c). Usage:
#   scripts/measure-rtv.sh [BUILD_DIR] [WIDTH LAYERS NUM_THETA NUM_PHI]   (default 32 8 4 8)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
cmake --build "$build" --target measure_rtv >/dev/null
"$build/measure_rtv" "${2:-32}" "${3:-8}" "${4:-4}" "${5:-8}"
