#!/usr/bin/env bash
# ParaView's default XDMF reader opens the run files of a 2D run (with checkpoints in the file) and a 1D run, and
# finds the particles, vectors and tensors, and the background grid (check_paraview.py), and those of a run on a
# triangle mesh with the mesh beside the particles (check_paraview_mesh.py).
# Usage: check_paraview.sh MPM SCENES_DIR
set -euo pipefail
mpm=$1 scenes=$2
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
"$mpm" run "$scenes/plate.json" --set 'grid.cells=[8,8]' --set output.every=100 --set output.checkpoint_every=200 \
  --out "$work/plate.h5" --summary plate.json --quiet
"$mpm" run "$scenes/bar.json" --set output.every=5 --out "$work/bar.h5" --summary bar.json --quiet
"$mpm" run "$scenes/plate-triangles.json" --set time.end=2.5e-3 --set output.every=10 --out "$work/tri.h5" \
  --summary tri.json --quiet
particles() { /usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["particles"])' "$1"; }
# grid nodes: 9 × 9 for the 8 × 8 plate, cells + 1 for the bar
bar_nodes=$(/usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["grid"]["cells"][0] + 1)' \
  "$scenes/bar.json")
xvfb-run -a pvpython "$here/check_paraview.py" "$work/plate.xdmf" "$(particles plate.json)" 81
xvfb-run -a pvpython "$here/check_paraview.py" "$work/bar.xdmf" "$(particles bar.json)" "$bar_nodes"
# the triangle mesh beside the particles: 1056 triangles in tools/meshes/plate_1058.msh
xvfb-run -a pvpython "$here/check_paraview_mesh.py" "$work/tri.xdmf" 1056 "$(particles tri.json)"
