#!/usr/bin/env bash
# The assimp test corpus (Debian's assimp-testmodels) as a test: meso info on every OBJ, PLY,
# glTF and GLB but invalid/, every loadable model rendered at 64 x 64 with every technique and
# the reference, checked against per-technique floors (scripts/test_assets.py; summary in
# docs/techniques.md, "Meshes nobody here made"). `make test-assets` runs it; CI too.
# Usage: scripts/test-assets.sh [build/meso] [extra options of test_assets.py]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
meso="${1:-$here/../build/meso}"
shift || true
exec python3 "$here/test_assets.py" --meso "$meso" "$@"
