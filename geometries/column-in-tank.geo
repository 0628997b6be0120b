// column-in-tank.geo -- a 2D soil column against the left wall of a water tank (plane strain,
// x-y plane, metres): the granular-collapse set-up of seed 004 (benchmarks D2, D3 in
// /work/shared/spec/benchmarks.md), the column held by a gate that is removed at t = 0.
//
// Dimensions: D2 uses a 200 x 32 grid of 0.0025 m cells (tank_length x tank_height = 0.5 x 0.08)
// and 12,288 particles at 16 per cell, i.e. a column of 0.0048 m^2. The paper gives the column
// only in a figure: column_width = 0.1 and column_height = 0.048 are assumed (their product is
// that area), and so is water_depth = 0.07 (the column under water, as in D2). For D3 ("half of
// the column in water") set water_depth = column_height / 2.
//
// Scene use: two bodies on this file, {"type": "gmsh", "file": "column-in-tank.geo",
// "physical": "column"} and the same with "physical": "water".
// Physical groups: surfaces "column", "water"; curves "tank_walls" (x = 0 and x = tank_length,
// full height), "tank_base", "gate" (the column's right side), "column_top", "water_surface".

DefineConstant[
  tank_length = 0.5,     // m
  tank_height = 0.08,    // m
  column_width = 0.1,    // m, from the left wall
  column_height = 0.048, // m
  water_depth = 0.07,    // m; not equal to column_height
  mesh_size = 0.005      // m
];

If (Fabs(water_depth - column_height) < 1e-9 * tank_height)
  Error("column-in-tank.geo: water_depth must differ from column_height");
EndIf
low = Min(water_depth, column_height);   // where the gate line is split
high = Max(water_depth, column_height);

// Left wall x = 0 from the bottom: 0, low, high, tank_height. Gate x = column_width: 0, low, (high).
Point(1) = {0, 0, 0, mesh_size};
Point(2) = {0, low, 0, mesh_size};
Point(3) = {0, high, 0, mesh_size};
Point(4) = {0, tank_height, 0, mesh_size};
Point(5) = {column_width, 0, 0, mesh_size};
Point(6) = {column_width, low, 0, mesh_size};
Point(7) = {tank_length, 0, 0, mesh_size};
Point(8) = {tank_length, water_depth, 0, mesh_size};
Point(9) = {tank_length, tank_height, 0, mesh_size};

Line(1) = {1, 5};  // base under the column
Line(2) = {5, 7};  // base under the water
Line(3) = {7, 8};  // right wall, wet
Line(4) = {8, 9};  // right wall, dry
Line(5) = {1, 2};  // left wall, lower part
Line(6) = {2, 3};  // left wall, middle part
Line(7) = {3, 4};  // left wall, above
Line(8) = {5, 6};  // gate, lower part

If (water_depth > column_height)
  // The column is under water: the water wraps its top.
  Line(9) = {6, 2};    // column top (low = column_height)
  Line(10) = {8, 3};   // water surface (high = water_depth)
  Curve Loop(1) = {1, 8, 9, -5};
  Curve Loop(2) = {2, 3, 10, -6, -9, -8};
  Physical Curve("gate") = {8};
  Physical Curve("column_top") = {9};
  Physical Curve("water_surface") = {10};
Else
  // The column stands out of the water: the gate line goes on above the water surface.
  Point(10) = {column_width, high, 0, mesh_size};
  Line(9) = {6, 10};   // gate, upper part
  Line(10) = {10, 3};  // column top (high = column_height)
  Line(11) = {8, 6};   // water surface (low = water_depth)
  Curve Loop(1) = {1, 8, 9, 10, -6, -5};
  Curve Loop(2) = {2, 3, 11, -8};
  Physical Curve("gate") = {8, 9};
  Physical Curve("column_top") = {10};
  Physical Curve("water_surface") = {11};
EndIf
Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Surface("column") = {1};
Physical Surface("water") = {2};
Physical Curve("tank_walls") = {5, 6, 7, 3, 4};
Physical Curve("tank_base") = {1, 2};
