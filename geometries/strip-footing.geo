// strip-footing.geo -- a soil layer under a strip load, 2D half model (plane strain, x-y plane,
// metres). Symmetric about x = 0: the model is the half 0 <= x <= width; the loaded strip is the
// part 0 <= x <= load_width of the top surface, the named curve "load".
//
// Dimensions: the strip-load consolidation benchmark A3 (seed 000) and the elastic strip footing
// B6 (seed 001, App. A), /work/shared/spec/benchmarks.md and seed-notes.md: a 10 m wide, 10 m deep
// half model, 20 kPa on 0-3 m ("load half-width 3.0").
//
// Scene use: {"type": "gmsh", "file": "strip-footing.geo"} with a load on face "load".
// Physical groups: surface "soil"; curves "load", "top" (load + free top), "top_free", "base",
// "right", "symmetry" (x = 0).

DefineConstant[
  width = 10,       // m, half width of the layer
  depth = 10,       // m, thickness of the layer
  load_width = 3,   // m, loaded part of the top, from the symmetry line
  mesh_size = 0.5   // m
];

Point(1) = {0, 0, 0, mesh_size};
Point(2) = {width, 0, 0, mesh_size};
Point(3) = {width, depth, 0, mesh_size};
Point(4) = {load_width, depth, 0, mesh_size};
Point(5) = {0, depth, 0, mesh_size};

Line(1) = {1, 2};  // base
Line(2) = {2, 3};  // right side
Line(3) = {3, 4};  // top, not loaded
Line(4) = {4, 5};  // top, loaded strip
Line(5) = {5, 1};  // symmetry line x = 0
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};

Physical Surface("soil") = {1};
Physical Curve("load") = {4};
Physical Curve("top_free") = {3};
Physical Curve("top") = {3, 4};
Physical Curve("base") = {1};
Physical Curve("right") = {2};
Physical Curve("symmetry") = {5};
