// The unit square [0, 1] x [0, 1] in unstructured (Frontal-Delaunay) triangles: n segments on each side and a target
// size h inside, set from the command line (gmsh -setnumber h 0.05 -setnumber n 20). The sides are divided
// explicitly because Gmsh's boundary division jumps by a whole segment as h varies, and with it the triangle count
// by ~10%; fixing n and varying h inside lands a count close to a target (1058 for the thesis' plate).
// The surface's normal is +z, so Gmsh writes its triangles counter-clockwise, as read_gmsh requires.
If (!Exists(h))
  h = 0.1;
EndIf
If (!Exists(n))
  n = Ceil(1 / h);
EndIf
Point(1) = {0, 0, 0, h};
Point(2) = {1, 0, 0, h};
Point(3) = {1, 1, 0, h};
Point(4) = {0, 1, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Transfinite Curve {1, 2, 3, 4} = n + 1;
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
// the size inside is h, not interpolated from the sides' points
Field[1] = MathEval;
Field[1].F = Sprintf("%g", h);
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.Algorithm = 6;  // Frontal-Delaunay
