// slope.geo -- a 2D soil slope (plane strain, x-y plane, metres): a foundation layer, the ground
// in front of the toe, the slope face and the crest. The same outline as the scene's parametric
// "slope" geometry (docs/scene-format.md has the drawing), as a gmsh file to edit further.
//
// Dimensions: the slope-stability benchmark B3 (Yuan et al. 2023, used by seed 001; see
// /work/shared/spec/benchmarks.md) gives its geometry only in a figure. The defaults give the
// 600 m^2 of soil that its particle count implies (seed-notes: "soil area ~ 600 m^2"):
// 45 m x 10 m foundation + 10 m x 10 m crest block + the 10 m x 10 m / 2 wedge of a 45 deg face.
//
// Scene use: {"type": "gmsh", "file": "slope.geo", "parameters": {"angle": 30}}
// Physical groups: surface "soil"; curves "surface" (toe + slope_face + crest), "toe",
// "slope_face", "crest", "base", "left", "right".

DefineConstant[
  foundation_depth = 10,  // m, layer below the toe
  height = 10,            // m, toe to crest
  angle = 45,             // deg, slope face from the horizontal
  toe_length = 25,        // m, ground in front of the toe
  crest_length = 10,      // m, crest behind the top of the face
  x0 = 0,                 // m, lower-left corner
  y0 = 0,                 // m
  mesh_size = 2           // m; straight edges: the mesh covers the outline exactly at any size
];

run = height / Tan(angle * Pi / 180);  // horizontal run of the slope face
length = toe_length + run + crest_length;

Point(1) = {x0, y0, 0, mesh_size};                                           // base, left
Point(2) = {x0 + length, y0, 0, mesh_size};                                  // base, right
Point(3) = {x0 + length, y0 + foundation_depth + height, 0, mesh_size};      // crest, right
Point(4) = {x0 + toe_length + run, y0 + foundation_depth + height, 0, mesh_size};  // top of the face
Point(5) = {x0 + toe_length, y0 + foundation_depth, 0, mesh_size};           // toe
Point(6) = {x0, y0 + foundation_depth, 0, mesh_size};                        // ground, left

Line(1) = {1, 2};  // base
Line(2) = {2, 3};  // right side
Line(3) = {3, 4};  // crest
Line(4) = {4, 5};  // slope face
Line(5) = {5, 6};  // ground in front of the toe
Line(6) = {6, 1};  // left side
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};

Physical Surface("soil") = {1};
Physical Curve("surface") = {5, 4, 3};
Physical Curve("toe") = {5};
Physical Curve("slope_face") = {4};
Physical Curve("crest") = {3};
Physical Curve("base") = {1};
Physical Curve("left") = {6};
Physical Curve("right") = {2};
