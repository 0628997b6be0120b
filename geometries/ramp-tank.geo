// ramp-tank.geo -- the subaerial granular slide tank of seed 004, benchmark D4 (Viroulet et al.
// 2013; /work/shared/spec/benchmarks.md section D), in 2D (plane strain, x-y plane, metres):
// a tank with a 45 deg inclined plane on the right, water in front of it, and a granular mass
// resting on the plane behind a vertical gate, its bottom at the water surface.
//
// Dimensions from the paper: tank 2.2 m long and 0.3 m high, 45 deg plane, water depth 0.148 m,
// mass bottom at the water level. Assumed: the plane ends at the top of the right wall
// (ramp_foot = tank_length - tank_height / tan(angle) = 1.9 m) and the mass is the triangle between
// the gate, the plane and a horizontal top; its height 0.144 m follows from the paper's 10,368
// particles at 16 per 0.004 m cell (0.010368 m^2 = mass_height^2 / (2 tan(angle))).
// The gate is where the plane crosses the water surface (x = 2.048 m); the wave gauges G1-G4 are
// 0.45, 0.75, 1.05, 1.35 m to its left.
//
// Scene use: bodies with "physical": "mass", "water" and "ramp" (the plane, an elastic solid).
// Physical groups: surfaces "mass", "water", "ramp"; curves "plane" (the inclined surface),
// "gate", "water_surface", "mass_top", "tank_walls" (x = 0 and x = tank_length), "tank_base".

DefineConstant[
  tank_length = 2.2,    // m
  tank_height = 0.3,    // m
  angle = 45,           // deg, the plane from the horizontal
  water_depth = 0.148,  // m
  mass_height = 0.144,  // m, above the water surface
  mesh_size = 0.01      // m
];

cot = 1 / Tan(angle * Pi / 180);
ramp_foot = tank_length - tank_height * cot;   // where the plane meets the base
gate = ramp_foot + water_depth * cot;          // where the plane meets the water surface
mass_right = gate + mass_height * cot;         // where the mass top meets the plane
If (water_depth + mass_height > tank_height)
  Error("ramp-tank.geo: water_depth + mass_height must not exceed tank_height");
EndIf

Point(1) = {0, 0, 0, mesh_size};
Point(2) = {ramp_foot, 0, 0, mesh_size};
Point(3) = {tank_length, 0, 0, mesh_size};
Point(4) = {tank_length, tank_height, 0, mesh_size};
Point(5) = {mass_right, water_depth + mass_height, 0, mesh_size};
Point(6) = {gate, water_depth, 0, mesh_size};
Point(7) = {gate, water_depth + mass_height, 0, mesh_size};
Point(8) = {0, water_depth, 0, mesh_size};
Point(9) = {0, tank_height, 0, mesh_size};

Line(1) = {1, 2};   // base under the water
Line(2) = {2, 3};   // base under the ramp
Line(3) = {3, 4};   // right wall
Line(4) = {4, 5};   // plane, above the mass
Line(5) = {5, 6};   // plane, under the mass
Line(6) = {6, 2};   // plane, under the water
Line(7) = {6, 8};   // water surface
Line(8) = {8, 1};   // left wall, wet
Line(9) = {8, 9};   // left wall, dry
Line(10) = {6, 7};  // gate
Line(11) = {7, 5};  // mass top

Curve Loop(1) = {1, -6, 7, 8};        // water
Curve Loop(2) = {2, 3, 4, 5, 6};      // ramp (below the plane)
Curve Loop(3) = {10, 11, 5};          // mass
Plane Surface(1) = {1};
Plane Surface(2) = {2};
Plane Surface(3) = {3};

Physical Surface("water") = {1};
Physical Surface("ramp") = {2};
Physical Surface("mass") = {3};
Physical Curve("plane") = {4, 5, 6};
Physical Curve("gate") = {10};
Physical Curve("water_surface") = {7};
Physical Curve("mass_top") = {11};
Physical Curve("tank_walls") = {8, 9, 3};
Physical Curve("tank_base") = {1, 2};
