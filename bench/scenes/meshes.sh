#!/usr/bin/env bash
# The meshes of bench/scenes/ that are too large to keep in the repository,
# written when missing by inputs/meshes/coupler_mesh.py (bench/newton.sh and
# make extremes call this).
set -u
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$here/meshes"
mesh=$here/meshes/coupler_10x44x10.mesh
if [ ! -s "$mesh" ]; then
    python3 "$here/../../inputs/meshes/coupler_mesh.py" 10 44 10 > "$mesh.tmp" &&
        mv "$mesh.tmp" "$mesh" || { echo "bench/scenes/meshes.sh: could not write $mesh" >&2; exit 1; }
fi
