#!/usr/bin/env python3
"""The same slide with explicit-double-point (seed 003), for the side-by-side comparison of the
README: water points instead of mpm-fem's grid water. What changes from the mpm-fem scene:
- the water gets a bulk modulus, K_L = 2 MPa (c = 44.7 m/s, 20 times the flow's 2 m/s: the weakly
  compressible water of examples/dam-break-double-point), and a hydrostatic start;
- solver keys only mpm-fem reads (solver.soil_substeps, air, phase_field) are dropped.
The gauges (water_level monitors) read explicit-double-point's water points.

Usage: python3 double_point.py scene.json [END] > scene-double-point.json
"""
import json
import sys

scene = json.load(open(sys.argv[1]))
scene["name"] = scene["name"] + "-double-point"
scene["formulation"] = "explicit-double-point"
for m in scene["materials"]:
    if m["model"] == "fluid":
        m["bulk_modulus"] = 2.0e6  # Pa
for b in scene["bodies"]:
    if "solid" not in b:
        b["initial"] = {"pore_pressure": "hydrostatic"}
scene.pop("solver", None)
if len(sys.argv) > 2:
    scene["time"]["end"] = float(sys.argv[2])
json.dump(scene, sys.stdout, indent=2)
print()
