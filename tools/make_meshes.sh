#!/usr/bin/env bash
# Writes the triangle meshes of tools/meshes/ (and the valid ones of tests/meshes/) from tools/meshes/unit_square.geo
# with Gmsh (Debian's gmsh 4.8.4 made the committed files; another version may place the nodes differently), as
# ASCII files that read_gmsh reads: Gmsh 2.2, and one 4.1 copy for the reader's tests. Prints each triangle count.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
geo="$root/tools/meshes/unit_square.geo"
command -v gmsh >/dev/null || { echo "make_meshes.sh: gmsh not found (apt-get install gmsh)" >&2; exit 1; }

# mesh OUT FORMAT H N: the unit square with n segments on each side and target size h inside
mesh() {
  gmsh -setnumber h "$3" -setnumber n "$4" -2 -format "$2" "$geo" -o "$1" >/dev/null
  local triangles
  if [ "$2" = msh22 ]; then  # element lines: number, type, ...; type 2 is the 3-node triangle
    triangles=$(awk '/^\$Elements/ { on = 1; getline; next } /^\$EndElements/ { on = 0 } on && $2 == 2 { n++ }
                     END { print n + 0 }' "$1")
  else
    triangles=$(awk '/^\$Elements/ { on = 1; getline; left = 0; next } /^\$EndElements/ { on = 0 }
                     on && left > 0 { left--; next }  # an element of the current block
                     on { left = $4; if ($3 == 2) n += $4 }  # a block: dimension, entity, type, count
                     END { print n + 0 }' "$1")
  fi
  printf '%-40s %6d triangles  (h = %s, %s segments a side)\n' "${1#"$root"/}" "$triangles" "$3" "$4"
}

out="$root/tools/meshes"
mesh "$out/unit_square_coarse.msh" msh22 0.125 8
# the thesis' plate (§6.3.1, 1058 triangles): 22 segments a side and h = 0.0475 inside give 1056
mesh "$out/plate_1058.msh" msh22 0.0475 22
# a convergence family: the size halves, the count about quadruples
mesh "$out/plate_h1.msh" msh22 0.1 10
mesh "$out/plate_h2.msh" msh22 0.05 20
mesh "$out/plate_h3.msh" msh22 0.025 40
# the reader's tests: one small mesh in both formats
mesh "$root/tests/meshes/square_small.msh" msh22 0.25 4
mesh "$root/tests/meshes/square_small_v41.msh" msh41 0.25 4
