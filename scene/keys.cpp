// The registries and the key tables of the scene file (keys.hpp): every key declared once, with its
// type, default, range, unit and meaning; named surfaces and face names.
#include <algorithm>

#include "scene/keys.hpp"

namespace swmpm::scene::detail {

// ------------------------------------------------------------------------------------------------
// Registries (keys.hpp).
// ------------------------------------------------------------------------------------------------

const std::vector<std::string>& solid_bc_names() {
  static const std::vector<std::string> v{"fixed", "roller", "free", "friction"};
  return v;
}
const std::vector<std::string>& fluid_bc_names() {
  static const std::vector<std::string> v{"impermeable", "drained", "pressure"};
  return v;
}
const std::vector<std::string>& face_names() {
  static const std::vector<std::string> v{"x_min", "x_max", "y_min", "y_max", "z_min", "z_max"};
  return v;
}
const std::vector<std::string>& geometry_types() {
  static const std::vector<std::string> v{"box", "polygon", "slope", "gmsh", "surface-mesh", "footing"};
  return v;
}
const std::vector<std::string>& point_quantities() {
  static const std::vector<std::string> v{
      "pore_pressure", "displacement_x", "displacement_y", "displacement_z", "velocity_x",
      "velocity_y",    "velocity_z",     "stress_xx",      "stress_yy",      "stress_zz",
      "stress_xy",     "stress_yz",      "stress_xz",      "mean_effective_stress",
      "deviatoric_stress", "porosity",   "plastic_strain", "water_level"};
  return v;
}
const std::vector<std::string>& global_quantities() {
  static const std::vector<std::string> v{"kinetic_energy", "strain_energy", "total_energy",
                                          "external_work"};
  return v;
}
const std::vector<std::string>& all_quantities() {
  static const std::vector<std::string> v = [] {
    auto all = point_quantities();
    for (const auto& q : global_quantities()) all.push_back(q);
    return all;
  }();
  return v;
}
bool is_3d_only_quantity(const std::string& q) {
  return q == "displacement_z" || q == "velocity_z" || q == "stress_yz" || q == "stress_xz";
}
bool needs_fluid_quantity(const std::string& q) {
  return q == "pore_pressure" || q == "porosity" || q == "water_level";
}

// -- the tables -----------------------------------------------------------------------------------
// Keys are written with designated initializers; fields left out keep their defaults on purpose.
// GCC before 14 warns about that under -Wextra, hence the pragma around the tables only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"

const Table& scene_table() {
  static const Table t{
      "Top level", "the scene object",
      {
          {.name = "name", .type = Type::custom, .required = true,
           .meaning = "Scene name; the default run directory is `runs/<name>`.",
           .type_text = "string", .expect = "a name usable as a directory: letters, digits, '.', '_', '-'",
           .allowed = "`[A-Za-z0-9._-]+`", .check = check_dir_name},
          {.name = "dimension", .type = Type::integer, .required = true, .range = closed(2, 3),
           .meaning = "2 (plane strain) or 3.", .expect = "2 or 3", .allowed = "2 or 3"},
          {.name = "formulation", .type = Type::choice, .def = "auto", .values = names_of(kFormulations),
           .meaning = "Solution scheme; `auto` picks one from the scene and says why."},
          {.name = "gravity", .type = Type::vector, .unit = "m/s^2",
           .meaning = "Gravitational acceleration.", .default_text = "zeros"},
          {.name = "gravity_ramp", .def = 0.0, .range = non_negative, .unit = "s",
           .meaning = "Gravity grows linearly from zero over this time (0: at once)."},
          {.name = "grid", .type = Type::object, .required = true,
           .meaning = "The background grid, see [grid](#grid)."},
          {.name = "materials", .type = Type::objects, .required = true,
           .meaning = "Materials, see [material](#material-every-model).", .nonempty = true},
          {.name = "bodies", .type = Type::objects, .required = true,
           .meaning = "Bodies, see [body](#body).", .nonempty = true},
          {.name = "boundaries", .type = Type::objects, .def = json::array(),
           .meaning = "Grid-face conditions, see [boundary](#boundary)."},
          {.name = "loads", .type = Type::objects, .def = json::array(),
           .meaning = "Surface loads on bodies, see [load](#load)."},
          {.name = "time", .type = Type::object, .required = true,
           .meaning = "End time and time step, see [time](#time)."},
          {.name = "output", .type = Type::object,
           .meaning = "Frames and monitors, see [output](#output).", .default_text = "all defaults"},
          {.name = "solver", .type = Type::object,
           .meaning = "Scheme switches, see [solver](#solver).", .default_text = "all defaults"},
          {.name = "initialisation", .type = Type::object,
           .meaning = "A phase before t = 0 that brings the bodies to equilibrium under gravity, see "
                      "[initialisation](#initialisation).",
           .default_text = "none"},
          {.name = "formulation_choice", .type = Type::object,
           .meaning = "Written by preprocess into `RUN_DIR/scene.json` when `formulation` was `auto`: how it chose "
                      "(`chosen`, `rule`, `reason`, `estimates`), echoed into `run.json`; a scene file leaves it out.",
           .default_text = "none"},
      }};
  return t;
}

const Table& grid_table() {
  static const Table t{
      "Grid", "`grid`",
      {
          {.name = "cell_size", .required = true, .range = positive, .unit = "m",
           .meaning = "Edge length of the square (2D) or cubic (3D) cells."},
          {.name = "min", .type = Type::vector, .required = true, .unit = "m",
           .meaning = "Lower corner of the grid."},
          {.name = "max", .type = Type::vector, .required = true, .unit = "m",
           .meaning = "Upper corner; > `min`; rounded up to a whole number of cells."},
          {.name = "shape_function", .type = Type::choice, .def = "gimp",
           .values = names_of(kShapeFunctions), .meaning = "Grid basis functions."},
      }};
  return t;
}

const Table& material_table() {
  static const Table t{
      "Material (every model)", "`materials[]`",
      {
          {.name = "name", .type = Type::string, .required = true,
           .meaning = "Unique name; bodies refer to it in `solid` / `fluid`."},
          {.name = "model", .type = Type::choice, .required = true, .values = names_of(kModels),
           .meaning = "Constitutive model; selects the parameter tables below."},
      }};
  return t;
}

const Table& solid_table() {
  static const Table t{
      "Solid skeleton (every model except `fluid`)", "`materials[]`",
      {
          {.name = "density", .range = positive, .unit = "kg/m^3",
           .meaning = "Bulk density of a dry body (instead of `grain_density` + `porosity`)."},
          {.name = "grain_density", .range = positive, .unit = "kg/m^3",
           .meaning = "Density of the grains; a porous skeleton, needs `porosity`."},
          {.name = "porosity", .range = open(0, 1), .unit = "-",
           .meaning = "Porosity n (pore volume / total volume)."},
          {.name = "hydraulic_conductivity", .range = positive, .unit = "m/s",
           .meaning = "Hydraulic conductivity k (or `intrinsic_permeability`, not both)."},
          {.name = "intrinsic_permeability", .range = positive, .unit = "m^2",
           .meaning = "Intrinsic permeability κ = k μ / (ρ_w g) (or `hydraulic_conductivity`)."},
          {.name = "permeability_law", .type = Type::choice, .def = "constant",
           .values = {"constant", "kozeny-carman", "xie-leo"},
           .meaning = "Permeability constant, varying with porosity (Kozeny–Carman: k = C1 n³/(1 − n)², C1 from the "
                      "initial n0 and k0), or with the volume ratio (`xie-leo`: k = k0 J², J = (1 − n0)/(1 − n), the law "
                      "behind Xie & Leo's large-strain consolidation closed form)."},
          {.name = "grain_diameter", .range = positive, .unit = "m",
           .meaning = "explicit-double-point, mpm-fem: reference grain diameter D (seed 004: D50); the intrinsic "
                      "permeability is then Kozeny–Carman's κ = D² n³ / (A (1 − n)²) (seed 003 eq. 11, seed 004; A = "
                      "`ergun_a`, 150 in both seeds), at the current porosity with `permeability_law` "
                      "`kozeny-carman`, at the initial one with `constant` (instead of `hydraulic_conductivity` / "
                      "`intrinsic_permeability`)."},
          {.name = "ergun_a", .def = 150.0, .range = positive, .unit = "-",
           .meaning = "explicit-double-point: Ergun's constant A of the viscous term (and of Kozeny–Carman), seed 003 eqs. 10–11."},
          {.name = "ergun_b", .def = 1.75, .range = non_negative, .unit = "-",
           .meaning = "explicit-double-point: Ergun's constant B of the inertial term, β = B / √(κ A n³) (seed 003 eq. 10)."},
          {.name = "maximum_porosity", .range = open(0, 1), .unit = "-",
           .meaning = "explicit-double-point: n_max; a solid point whose porosity exceeds it is liquefied (zero "
                      "effective stress, the pore liquid viscous) until it falls below it again (sedimentation). "
                      "Absent: the skeleton never liquefies."},
      }};
  return t;
}

const Table& elastic_table() {
  static const Table t{
      "Elasticity (`linear-elastic`, `hencky`, `mohr-coulomb`, `drucker-prager`)", "`materials[]`",
      {
          {.name = "youngs_modulus", .required = true, .range = positive, .unit = "Pa",
           .meaning = "Young's modulus E."},
          {.name = "poisson_ratio", .required = true, .range = half_open(-1, 0.5), .unit = "-",
           .meaning = "Poisson's ratio ν."},
      }};
  return t;
}

const Table& strength_table() {
  static const Table t{
      "Strength (`mohr-coulomb`, `drucker-prager`)", "`materials[]`",
      {
          {.name = "cohesion", .def = 0.0, .range = non_negative, .unit = "Pa",
           .meaning = "Cohesion c."},
          {.name = "friction_angle", .required = true, .range = half_open(0, 90), .unit = "deg",
           .meaning = "Friction angle φ."},
          {.name = "dilation_angle", .def = 0.0, .range = half_open(0, 90), .unit = "deg",
           .meaning = "Dilation angle ψ (0: no dilatancy).", .allowed = "[0, `friction_angle`]"},
          {.name = "strength_reduction_factor", .def = 1.0, .range = positive, .unit = "-",
           .meaning = "c and tan φ are divided by it (slope stability; 1: none)."},
          {.name = "tension_cutoff", .def = 0.0, .range = non_negative, .unit = "Pa",
           .meaning = "Tensile strength limit on the mean stress (0: no tension)."},
      }};
  return t;
}

const Table& nor_sand_table() {
  static const Table t{
      "Nor-Sand (`nor-sand`)", "`materials[]`",
      {
          {.name = "shear_modulus", .required = true, .range = positive, .unit = "Pa",
           .meaning = "Elastic shear modulus μ0 (G; the shear modulus at zero `shear_modulus_coupling`)."},
          {.name = "shear_modulus_coupling", .def = 0.0, .range = non_negative, .unit = "-",
           .meaning = "α0 of Borja & Andrade's hyperelasticity: μ_e = μ0 + α0 p̂ (0: constant shear modulus)."},
          {.name = "swelling_index", .required = true, .range = positive, .unit = "-",
           .meaning = "Elastic compressibility κ̃ = −dε_v^e / d ln p′ (logarithmic strain; ≈ κ / v)."},
          {.name = "reference_pressure", .def = 2.0e3, .range = positive, .unit = "Pa",
           .meaning = "Pressure p_ref of the hyperelastic law at `reference_elastic_volumetric_strain`."},
          {.name = "reference_elastic_volumetric_strain", .def = 0.0, .range = any_number, .unit = "-",
           .meaning = "Elastic volumetric strain ε_v0^e at `reference_pressure` (tension positive)."},
          {.name = "compression_index", .required = true, .range = positive, .unit = "-",
           .meaning = "Slope λ̃ of the critical state line in v–ln p′."},
          {.name = "reference_specific_volume", .required = true, .range = positive, .unit = "-",
           .meaning = "Specific volume v_c0 of the critical state line at `csl_reference_pressure`."},
          {.name = "csl_reference_pressure", .def = 1.0e3, .range = positive, .unit = "Pa",
           .meaning = "Pressure unit of the critical state line: v_c = v_c0 − λ̃ ln(p′ / p_csl)."},
          {.name = "critical_state_ratio", .required = true, .range = positive, .unit = "-",
           .meaning = "Critical state stress ratio M (triaxial compression)."},
          {.name = "yield_coefficient", .required = true, .range = half_open(0, 1), .unit = "-",
           .meaning = "Shape coefficient N of the yield surface (0: the logarithmic form)."},
          {.name = "potential_coefficient", .required = true, .range = half_open(0, 1), .unit = "-",
           .meaning = "Shape coefficient N̄ of the plastic potential (N̄ = N: associated)."},
          {.name = "hardening_modulus", .required = true, .range = positive, .unit = "-",
           .meaning = "Hardening coefficient h of the image pressure: π̇_i = h (π_i* − π_i) ε̇_s^p."},
          {.name = "dilatancy_multiplier", .required = true, .range = any_number, .unit = "-",
           .meaning = "α of the maximum plastic dilatancy α ψ_i (negative, e.g. −3.5)."},
          {.name = "initial_specific_volume", .required = true, .range = positive, .unit = "-",
           .meaning = "Specific volume v0 = 1 + e0 at F = I; v = J v0."},
          {.name = "overconsolidation_ratio", .def = 1.0, .range = at_least(1), .unit = "-",
           .meaning = "OCR: the initial image pressure is OCR × the one that puts the first stress on the yield surface."},
          {.name = "dilatancy_cutoff_start", .def = 1.0, .range = positive, .unit = "-",
           .meaning = "Accumulated deviatoric plastic strain Ē_d^p where ψ_i starts fading to 0 (1 = 100 %)."},
          {.name = "dilatancy_cutoff_end", .def = 1.5, .range = positive, .unit = "-",
           .meaning = "Ē_d^p where ψ_i reaches 0 (≥ `dilatancy_cutoff_start`)."},
          {.name = "gas_specific_volume_ratio", .def = 1.6, .range = positive, .unit = "-",
           .meaning = "v_crit / v0: above v_crit the stress is zero (gas-like, reversible)."},
      }};
  return t;
}

const Table& fluid_table() {
  static const Table t{
      "Fluid (`fluid`)", "`materials[]`",
      {
          {.name = "density", .required = true, .range = positive, .unit = "kg/m^3",
           .meaning = "Fluid density ρ_w."},
          {.name = "bulk_modulus", .range = positive, .unit = "Pa",
           .meaning = "Fluid bulk modulus K_w; required by every coupled formulation but mpm-fem, whose water is "
                      "incompressible (and which refuses it)."},
          {.name = "dynamic_viscosity", .def = 1.0e-3, .range = positive, .unit = "Pa s",
           .meaning = "Dynamic viscosity μ (turns `intrinsic_permeability` into conductivity; explicit-double-point: "
                      "the Newtonian viscosity of free water and the base of a liquefied mixture's)."},
          {.name = "cavitation_threshold", .def = 0.0, .range = non_negative, .unit = "Pa",
           .meaning = "explicit-double-point: the largest tension the liquid carries; its pressure is kept at or above "
                      "−`cavitation_threshold` (seed 003: 0, no tension)."},
      }};
  return t;
}

const Table& body_table() {
  static const Table t{
      "Body", "`bodies[]`",
      {
          {.name = "name", .type = Type::string, .required = true,
           .meaning = "Unique name; loads refer to it."},
          {.name = "geometry", .type = Type::object, .required = true,
           .meaning = "Where the body is, see [geometry](#geometry-every-type)."},
          {.name = "solid", .type = Type::string,
           .meaning = "Name of a solid material (the skeleton)."},
          {.name = "fluid", .type = Type::string,
           .meaning = "Name of a `fluid` material (pore fluid, or free fluid without `solid`: `explicit-double-point` and `mpm-fem` only)."},
          {.name = "particles_per_cell", .type = Type::integer, .def = 2, .range = closed(1, 32),
           .meaning = "Particles per cell and direction (n^dimension per cell)."},
          {.name = "initial", .type = Type::object,
           .meaning = "Initial state, see [initial state](#initial-state).", .default_text = "all defaults"},
      }};
  return t;
}

const Table& geometry_table() {
  static const Table t{
      "Geometry (every type)", "`bodies[].geometry`",
      {
          {.name = "type", .type = Type::choice, .required = true, .values = geometry_types(),
           .meaning = "Kind of geometry; its keys are in the table of that type below."},
      }};
  return t;
}

const Table& box_table() {
  static const Table t{
      "Box (`box`)", "`bodies[].geometry`",
      {
          {.name = "min", .type = Type::vector, .required = true, .unit = "m",
           .meaning = "Lower corner; inside the grid."},
          {.name = "max", .type = Type::vector, .required = true, .unit = "m",
           .meaning = "Upper corner; > `min` in every component, inside the grid."},
      }};
  return t;
}

const Table& polygon_table() {
  static const Table t{
      "Polygon (`polygon`, 2D only)", "`bodies[].geometry`",
      {
          {.name = "vertices", .type = Type::custom, .required = true, .unit = "m",
           .meaning = "Corners in order (either orientation); non-zero area, inside the grid.",
           .type_text = "array of [x, y]", .expect = "an array of at least 3 [x, y] pairs",
           .allowed = "≥ 3 vertices", .check = check_vertices},
      }};
  return t;
}

const Table& slope_table() {
  static const Table t{
      "Slope (`slope`, 2D only)", "`bodies[].geometry`",
      {
          {.name = "foundation_depth", .required = true, .range = positive, .unit = "m",
           .meaning = "Thickness of the foundation layer, from its base up to the toe."},
          {.name = "height", .required = true, .range = positive, .unit = "m",
           .meaning = "Height of the slope, from the toe up to the crest."},
          {.name = "angle", .range = open(0, 90), .unit = "deg",
           .meaning = "Inclination of the slope face from the horizontal (or `ratio`, exactly one)."},
          {.name = "ratio", .range = positive, .unit = "-",
           .meaning = "Slope face gradient horizontal : vertical, e.g. 2 for 1V:2H (or `angle`)."},
          {.name = "crest_length", .required = true, .range = positive, .unit = "m",
           .meaning = "Horizontal length of the crest, from the top of the face to the right side."},
          {.name = "toe_length", .required = true, .range = positive, .unit = "m",
           .meaning = "Horizontal length of the ground in front of the toe, from the left side."},
          {.name = "origin", .type = Type::vector, .unit = "m",
           .meaning = "Lower-left corner of the foundation.", .default_text = "grid `min`"},
      }};
  return t;
}

const Table& footing_table() {
  static const Table t{
      "Footing (`footing`)", "`bodies[].geometry`",
      {
          {.name = "width", .required = true, .range = positive, .unit = "m",
           .meaning = "Extent along x."},
          {.name = "height", .required = true, .range = positive, .unit = "m",
           .meaning = "Extent along y (the block's thickness)."},
          {.name = "center_x", .required = true, .range = any_number, .unit = "m",
           .meaning = "x of the block's centre."},
          {.name = "center_z", .range = any_number, .unit = "m",
           .meaning = "z of the block's centre; required in 3D, only there."},
          {.name = "length", .range = positive, .unit = "m",
           .meaning = "Extent along z; required in 3D, only there."},
          {.name = "on", .type = Type::string,
           .meaning = "Name of the body the block rests on: its base is that body's top (highest point); "
                      "or give `base_y`."},
          {.name = "base_y", .range = any_number, .unit = "m",
           .meaning = "Height of the block's base (instead of `on`)."},
      }};
  return t;
}

const Table& gmsh_table() {
  static const Table t{
      "Gmsh (`gmsh`)", "`bodies[].geometry`",
      {
          {.name = "file", .type = Type::custom, .required = true, .values = {".geo", ".msh"},
           .meaning = "Gmsh file, relative to the scene file's folder; a `.geo` is meshed when preprocess reads it.",
           .type_text = "string", .expect = "a path to an existing .geo or .msh file",
           .allowed = "`.geo`, `.msh`", .check = check_file},
          {.name = "parameters", .type = Type::custom, .def = json::object(), .unit = "as in the file",
           .meaning = "Values for the `.geo` file's `DefineConstant` variables, by name (not with `.msh`).",
           .type_text = "object of numbers", .expect = "an object of numbers keyed by DefineConstant names",
           .allowed = "`DefineConstant` names", .default_text = "none", .check = check_parameters},
          {.name = "physical", .type = Type::string,
           .meaning = "Physical group forming the body: a surface group (2D) or volume group (3D); "
                      "default: every surface (2D) / volume (3D) of the file."},
      }};
  return t;
}

const Table& surface_mesh_table() {
  static const Table t{
      "Surface mesh (`surface-mesh`, 3D only)", "`bodies[].geometry`",
      {
          {.name = "file", .type = Type::custom, .required = true, .values = {".off", ".stl", ".obj"},
           .meaning = "Closed, not self-intersecting surface mesh, relative to the scene file's folder.",
           .type_text = "string", .expect = "a path to an existing .off, .stl or .obj file",
           .allowed = "`.off`, `.stl`, `.obj`", .check = check_file},
      }};
  return t;
}

const Table& initial_table() {
  static const Table t{
      "Initial state", "`bodies[].initial`",
      {
          {.name = "pore_pressure", .type = Type::custom, .unit = "Pa",
           .meaning = "Initial pore pressure (compression positive), or hydrostatic; needs a body `fluid`.",
           .type_text = "number or string", .expect = "a number or \"hydrostatic\"",
           .allowed = "any, or `\"hydrostatic\"`", .check = check_pore_pressure},
          {.name = "water_table", .range = any_number, .unit = "m",
           .meaning = "Height of the free water surface for `\"hydrostatic\"` (default: top of the body); the soil above it is dry."},
          {.name = "stress", .type = Type::custom, .unit = "Pa",
           .meaning = "Initial effective stress: `\"geostatic\"`, or constant Voigt [xx, yy, zz, xy, yz, xz], tension positive.",
           .type_text = "string or 6 numbers", .expect = "\"geostatic\" or an array of 6 numbers (xx, yy, zz, xy, yz, xz)",
           .allowed = "`\"geostatic\"` or 6 numbers", .check = check_stress},
          {.name = "k0", .def = 0.5, .range = closed(0, 10), .unit = "-",
           .meaning = "Lateral earth pressure coefficient (only with `\"geostatic\"`)."},
          {.name = "porosity", .range = open(0, 1), .unit = "-",
           .meaning = "Initial porosity; overrides the material's."},
          {.name = "velocity", .type = Type::custom, .unit = "m/s",
           .meaning = "Initial velocity; each component a number or a muParser expression in x, y, z (`pi` defined).",
           .type_text = "`dimension` numbers or strings",
           .expect = "an array of one number or expression per dimension", .allowed = "expressions in x, y, z",
           .default_text = "zeros", .check = check_velocity},
      }};
  return t;
}

const Table& boundary_table() {
  static const Table t{
      "Boundary", "`boundaries[]`",
      {
          {.name = "on", .type = Type::string, .required = true,
           .meaning = "Grid face (`z_min`, `z_max` only in 3D), or a geometry's named surface (a rigid "
                      "wall along it); each at most once.",
           .allowed = "`x_min`, `x_max`, `y_min`, `y_max`, `z_min`, `z_max`, or a named surface"},
          {.name = "solid", .type = Type::choice, .def = "free", .values = solid_bc_names(),
           .meaning = "Solid velocity condition: fixed (all components), roller (normal), free, friction."},
          {.name = "coefficient", .range = non_negative, .unit = "-",
           .meaning = "Coulomb friction coefficient; required with `friction`, only there."},
          {.name = "fluid", .type = Type::choice, .values = fluid_bc_names(),
           .meaning = "Fluid condition: no flow, p = 0, or p = `value`; needs a fluid in the scene."},
          {.name = "value", .range = any_number, .unit = "Pa",
           .meaning = "Prescribed pore pressure; required with `pressure`, only there."},
      }};
  return t;
}

const Table& load_table() {
  static const Table t{
      "Load", "`loads[]`",
      {
          {.name = "type", .type = Type::choice, .required = true, .values = {"traction", "pressure"},
           .meaning = "A traction vector, or a pressure normal to the face."},
          {.name = "body", .type = Type::string, .required = true,
           .meaning = "Name of the loaded body."},
          {.name = "face", .type = Type::string, .required = true,
           .meaning = "The body's surface layer facing that way (`z_*` only in 3D), or along one of its "
                      "named surfaces.",
           .allowed = "`x_min`, `x_max`, `y_min`, `y_max`, `z_min`, `z_max`, or a named surface"},
          {.name = "value", .type = Type::custom, .required = true, .unit = "Pa",
           .meaning = "traction: a `dimension`-vector; pressure: a number, positive pushing onto the face.",
           .type_text = "vector or number", .expect = "a vector of one number per dimension (traction) or a number (pressure)",
           .allowed = "any", .check = check_load_value},
          {.name = "region", .type = Type::object,
           .meaning = "Load only the face particles inside this box at t = 0, see [region](#region)."},
          {.name = "ramp", .def = 0.0, .range = non_negative, .unit = "s",
           .meaning = "The load grows linearly from zero over this time (0: at once)."},
          {.name = "function", .type = Type::custom, .unit = "-",
           .meaning = "Multiplier f(t): a muParser expression in t (`pi` defined), e.g. `\"sin(5*pi*t)\"`.",
           .type_text = "string", .expect = "an expression in t", .allowed = "expression in t",
           .check = check_time_expression},
          {.name = "table", .type = Type::custom, .unit = "-",
           .meaning = "Multiplier f(t) as [t, f] pairs, piecewise linear, clamped; not with `function`.",
           .type_text = "array of [t, f]", .expect = "a non-empty array of [t, f] pairs",
           .allowed = "t strictly increasing", .check = check_time_table},
      }};
  return t;
}

const Table& region_table() {
  static const Table t{
      "Region", "`loads[].region`",
      {
          {.name = "min", .type = Type::vector, .required = true, .unit = "m", .meaning = "Lower corner."},
          {.name = "max", .type = Type::vector, .required = true, .unit = "m",
           .meaning = "Upper corner; > `min` in every component."},
      }};
  return t;
}

const Table& time_table() {
  static const Table t{
      "Time", "`time`",
      {
          {.name = "end", .required = true, .range = positive, .unit = "s", .meaning = "Simulated end time."},
          {.name = "dt", .type = Type::custom, .def = "auto", .unit = "s",
           .meaning = "Time step, or `\"auto\"`: the critical step of the formulation times `cfl`.",
           .type_text = "number or string", .expect = "a positive number or \"auto\"",
           .allowed = "> 0 or `\"auto\"`", .check = check_dt},
          {.name = "cfl", .def = 0.5, .range = left_open(0, 1), .unit = "-",
           .meaning = "Courant number used with `\"auto\"`."},
      }};
  return t;
}

const Table& output_table() {
  static const Table t{
      "Output", "`output`",
      {
          {.name = "interval", .def = 0.0, .range = non_negative, .unit = "s",
           .meaning = "Simulated time between VTU frames (0: first and last only)."},
          {.name = "monitor_interval", .def = 0.0, .range = non_negative, .unit = "s",
           .meaning = "Simulated time between rows of monitors.csv (0: every step)."},
          {.name = "compression", .type = Type::choice, .def = "zlib", .values = {"zlib", "lz4", "none"},
           .meaning = "Compression of the VTU frames' binary data: `zlib` (level 1; read by every VTU reader), "
                      "`lz4` (frames written about 7 times faster, files about 35 % larger; VTK-based readers "
                      "such as ParaView read it, some standalone readers do not) or `none` (fastest, files about "
                      "2.3 times zlib's). B4 12^2 double-point frame (172k points): 0.34 / 0.048 / 0.035 s "
                      "(docs/verification.md)."},
          {.name = "checkpoint_interval", .range = positive, .unit = "s",
           .meaning = "Simulated time between restart checkpoints on disk (`RUN_DIR/checkpoint.bin`, the latest "
                      "only; under mpirun with each rank's particles in `RUN_DIR/checkpoint/piece-<n>-<rank>.bin`), "
                      "from which `swmpm solve RUN_DIR --resume` continues; absent: one with every frame. "
                      "Not `solver.checkpoint_every`, the in-memory last-good snapshots.",
           .default_text = "with every frame"},
          {.name = "monitors", .type = Type::objects, .def = json::array(),
           .meaning = "Time histories, see [monitor](#monitor)."},
      }};
  return t;
}

const Table& monitor_table() {
  static const Table t{
      "Monitor", "`output.monitors[]`",
      {
          {.name = "name", .type = Type::custom, .required = true,
           .meaning = "Unique; CSV columns are `<name>.<quantity>`.", .type_text = "string",
           .expect = "a name of letters, digits, '_', '-'", .allowed = "`[A-Za-z0-9_-]+`",
           .check = check_monitor_name},
          {.name = "at", .type = Type::custom, .unit = "m",
           .meaning = "Follow the particle of `phase` nearest to this point at t = 0; in a `water_level` gauge, "
                      "the gauge's vertical line: x (2D) or x, z (3D).",
           .type_text = "vector", .allowed = "`dimension` numbers; `dimension` − 1 in a `water_level` gauge",
           .check = check_monitor_at},
          {.name = "particle", .type = Type::integer, .range = at_least(0),
           .meaning = "Or follow this particle id (not with `at`)."},
          {.name = "phase", .type = Type::choice, .def = "solid", .values = {"solid", "fluid"},
           .meaning = "Which phase's particle (`fluid` needs a fluid in the scene). In the double-point formulations "
                      "every point monitor follows a soil point, whatever `phase` says: the soil points carry the "
                      "water's pore pressure and velocity interpolated from the water points (docs/architecture.md), "
                      "and the log names the soil particle followed. In mpm-fem a `fluid` monitor with `at` is an "
                      "Eulerian probe: it reads the grid's fluid at that fixed point (`pore_pressure`, `velocity_*`)."},
          {.name = "points", .type = Type::choice, .def = "soil", .values = {"soil", "water"},
           .meaning = "Which particle set a point monitor follows: `water` follows a water point of a double-point "
                      "formulation (`at`: the nearest at t = 0, or `particle`: its id), e.g. one at a free surface, "
                      "and may record `displacement_*`, `velocity_*` (the water's), `pore_pressure`, `porosity`."},
          {.name = "quantities", .type = Type::choices, .required = true, .values = all_quantities(),
           .meaning = "What to record; see [monitor rules](#monitor-rules) for which need what.", .nonempty = true},
      }};
  return t;
}

const Table& solver_table() {
  static const Table t{
      "Solver", "`solver`",
      {
          {.name = "flip", .def = 0.99, .range = closed(0, 1), .unit = "-",
           .meaning = "FLIP fraction of the FLIP/PIC velocity update (1: pure FLIP)."},
          {.name = "damping", .def = 0.0, .range = half_open(0, 1), .unit = "-",
           .meaning = "Local (Cundall) damping coefficient."},
          {.name = "kinematics", .type = Type::choice, .def = "finite-strain",
           .values = {"small-strain", "finite-strain"}, .meaning = "Strain measure of the `mohr-coulomb` update (`drucker-prager`, `nor-sand`: finite strain only); refused when no material reads it."},
          {.name = "continuity", .type = Type::choice,
           .values = {"non-conservative", "conservative"},
           .meaning = "Two-phase mixture volume balance: `non-conservative` (1 − n) div v_s + n div v_w "
                      "(the seeds' eq. 9 / eq. 60) or `conservative` div[(1 − n) v_s + n v_w], which adds "
                      "(v_w − v_s)·grad n (needed at large strain, A2 and B2; see docs/formulations.md); in "
                      "explicit-single-point it also adds the interaction force p grad n between the phases; "
                      "default by formulation: `conservative` (semi-implicit), `non-conservative` otherwise "
                      "(explicit-single-point: the seed's eq. 9)."},
          {.name = "escaped_water", .type = Type::choice, .def = "keep", .values = {"keep", "remove"},
           .meaning = "Double-point only: water points that have left the soil (the soil's volume fraction "
                      "interpolated at the point below one half) stay as free water (`keep`) or leave the "
                      "run (`remove`: an outflow through a drained free surface into a reservoir that is not "
                      "modelled, as in B2; see docs/formulations.md)."},
          {.name = "drag_integration", .type = Type::choice, .values = {"implicit", "semi-implicit", "explicit"},
           .meaning = "Semi-implicit formulations: the soil–water drag of the predictor implicit in both "
                      "phases' velocities (`implicit`, the default) or in the water's only, the soil taking "
                      "it from v_w* and its own v_s^t (`semi-implicit`, seed 001 eqs. 52–53). The seed's "
                      "form amplifies the relative velocity by about M_w/M_s where the drag is stiff, so a "
                      "node with much more water than soil (free water over soil, a seepage exit) diverges; "
                      "see docs/formulations.md, \"Implicit drag\". mpm-fem: the drag in the fluid's "
                      "equations with its new velocity (`implicit`, the default) or its old one (`explicit`, "
                      "seed 004 eqs. 64–66, stable only below dt = 2 ρ / (n μ / k))."},
          {.name = "drag", .type = Type::choice, .values = {"darcy", "ergun"},
           .meaning = "explicit-double-point: the soil–liquid drag, `darcy` n² μ / κ (v_L − v_S) or `ergun` (the "
                      "default), which adds β n³ ρ_L ‖v_L − v_S‖ (v_L − v_S), β = B / √(κ A n³) (seed 003 eqs. 9–10)."},
          {.name = "checkpoint_every", .type = Type::integer, .def = 50, .range = at_least(1),
           .meaning = "Steps between in-memory snapshots of the last good state."},
          {.name = "soil_substeps", .type = Type::integer, .def = 1, .range = closed(1, 1000),
           .meaning = "mpm-fem only: soil steps per step of the fluid and the phase field (multi-rate). The "
                      "soil's explicit step is limited by its P-wave speed, the Eulerian water's by its flow "
                      "(h over its speed), the soil–fluid coupling and the phase field's reaction, often tens of times "
                      "longer; with k substeps the fluid advances once by the time the soil reaches after k "
                      "steps and the soil takes its pressure and drag meanwhile. dt auto keeps the fluid's "
                      "limits for k Δt. 1 is the seed's scheme (docs/formulations.md, \"Multi-rate\")."},
          {.name = "stabilisation", .type = Type::object,
           .meaning = "See [stabilisation](#stabilisation).", .default_text = "all defaults"},
          {.name = "air", .type = Type::object,
           .meaning = "mpm-fem only: the air above the water, see [air](#air).", .default_text = "all defaults"},
          {.name = "phase_field", .type = Type::object,
           .meaning = "mpm-fem only: the phase field of the water's free surface, see [phase field](#phase-field).",
           .default_text = "all defaults"},
      }};
  return t;
}

const Table& air_table() {
  static const Table t{
      "Air", "`solver.air` (mpm-fem only)",
      {
          {.name = "density", .def = 1.2, .range = positive, .unit = "kg/m^3",
           .meaning = "Density ρ_g of the air, the fluid where the phase field φ = 0; the fluid's density is "
                      "φ ρ_w + (1 − φ) ρ_g (seed 004)."},
          {.name = "dynamic_viscosity", .def = 1.8e-5, .range = positive, .unit = "Pa s",
           .meaning = "Dynamic viscosity μ_g of the air; the fluid's is φ μ_w + (1 − φ) μ_g (seed 004)."},
          {.name = "domain", .type = Type::choice, .def = "active", .values = {"active", "grid"},
           .meaning = "Where the fluid (water and air) is solved. `active`: on the box of cells that hold water "
                      "(φ > 0.01 at a node) or soil, widened by p + 1 cells (p the B-splines' degree) and "
                      "grown when they come within p cells of its edge; where the box ends inside the grid its "
                      "faces are open (p = 0, as a grid face not listed in `boundaries`), and the air beyond is "
                      "at rest. `grid`: the whole grid, as seed 004 (docs/formulations.md, \"Active region\")."},
      }};
  return t;
}

const Table& phase_field_table() {
  static const Table t{
      "Phase field", "`solver.phase_field` (mpm-fem only)",
      {
          {.name = "interface_width", .range = positive, .unit = "m",
           .meaning = "Width of the diffuse water–air interface of the Allen–Cahn phase field φ (1 water, 0 air; "
                      "seed 004), from φ = 0.05 to 0.95: 2.944 δ of the planar profile (1 + tanh(x/δ))/2, from "
                      "which the gradient coefficient a follows (W = 1; docs/formulations.md, \"The phase field\").",
           .default_text = "3 `cell_size`"},
          {.name = "mobility", .range = positive, .unit = "1/s",
           .meaning = "Mobility of the Allen–Cahn equation ∂φ/∂t + v·∇φ = M_φ (a² ∇²φ + 4 W φ (1 − φ)(φ − ½)) "
                      "with W = 1: M_φ W, the rate at which the interface relaxes to its profile. A curved "
                      "interface moves at M_φ a² κ: the dam break's front fell 16 % behind Martin & Moyce at 500 "
                      "(docs/formulations.md).",
           .default_text = "`200`"},
          {.name = "lsic", .type = Type::boolean, .def = false,
           .meaning = "The seed's LSIC diffusion (h/2)|v| ∇²φ in the phase field's equation (App. B, eq. 96). Off by "
                      "default: it smears a thin surge front, which then lags (the dam break: −16 % at T = 3 with it, "
                      "+1 % without)."},
          {.name = "volume_correction", .type = Type::boolean, .def = true,
           .meaning = "Restore the water volume ∫ n φ dΩ after each step by φ += λ 4φ(1 − φ) (Allen–Cahn's "
                      "curvature flow loses water at convex surfaces; docs/formulations.md)."},
      }};
  return t;
}

const Table& initialisation_table() {
  static const Table t{
      "Initialisation", "`initialisation`",
      {
          {.name = "duration", .required = true, .range = positive, .unit = "s",
           .meaning = "Length of the phase; it runs from t = −duration to 0, the analysis from 0 to `time.end`."},
          {.name = "gravity_ramp", .range = non_negative, .unit = "s",
           .meaning = "Gravity grows linearly from zero over this time from the start of the phase (≤ `duration`); "
                      "the top-level `gravity_ramp` must then be 0.",
           .default_text = "`duration`"},
          {.name = "plasticity", .type = Type::boolean, .def = false,
           .meaning = "Plastic flow during the phase (false: every material responds elastically; Nor-Sand's image "
                      "pressure is set from the stress at t = 0)."},
          {.name = "hydraulic_conductivity", .range = positive, .unit = "m/s",
           .meaning = "Hydraulic conductivity of every porous material during the phase (e.g. 1 m/s: the pore "
                      "pressures dissipate as gravity grows).",
           .default_text = "the materials' own"},
          {.name = "tie_water", .type = Type::boolean, .def = true,
           .meaning = "Double-point formulations: each water point follows its coincident soil point during the "
                      "phase (no seepage of the points; the grid still solves the flow)."},
          {.name = "damping", .range = half_open(0, 1), .unit = "-",
           .meaning = "Local damping during the phase.", .default_text = "`solver.damping`"},
          {.name = "reset_displacement", .type = Type::boolean, .def = true,
           .meaning = "Displacements (frames, monitors) are measured from the state at t = 0."},
          {.name = "materials", .type = Type::custom, .unit = "as the parameters",
           .meaning = "Material parameters in place of the scene's while the phase runs, by material name: "
                      "`{\"sand\": {\"cohesion\": 1e5}}` (e.g. a large cohesion while gravity grows, c = 0 from "
                      "t = 0, as seed 004 does). Only the parameters of the material's constitutive model "
                      "(elasticity, strength, Nor-Sand tables); every formulation.",
           .type_text = "object of objects", .expect = "an object of objects: material name -> {parameter: number}",
           .allowed = "solid materials' model parameters", .default_text = "none",
           .check = check_phase_materials},
      }};
  return t;
}

const Table& stabilisation_table() {
  static const Table t{
      "Stabilisation", "`solver.stabilisation`",
      {
          {.name = "strain_smoothing", .type = Type::boolean, .def = true,
           .meaning = "Smooth volumetric strain over cells."},
          {.name = "pressure", .type = Type::choice,
           .values = {"none", "mfvp-constant", "mfvp-linear", "mfvp-quadratic", "node-remap", "cell-constant",
                      "pspg", "pspg-increment"},
           .meaning = "Pore-pressure stabilisation; default by formulation: `mfvp-linear` "
                      "(explicit-single-point, semi-implicit, explicit-double-point: on the liquid points' "
                      "pressure rate), `pspg` (mpm-fem), `none` otherwise. `cell-constant` "
                      "(explicit-single-point): one pressure per grid cell, its rate the exact transpose of "
                      "the pressure forces. mpm-fem: PSPG on the seed's full momentum residual (`pspg`) or on its "
                      "increment over the step (`pspg-increment`; docs/formulations.md)."},
          {.name = "fbar", .type = Type::choice, .def = "none", .values = {"none", "standard", "modified"},
           .meaning = "F-bar treatment of volumetric locking (seed 001 §4.4.2, every formulation): `standard` "
                      "scales ΔF by the node-wise average of det ΔF (eqs. 79-80); `modified` also averages the "
                      "elastic J^e over fixed patches (eqs. 81-83)."},
          {.name = "fbar_patch", .range = closed(1, 4), .unit = "-",
           .meaning = "Modified F-bar: patch side h_patch / h of the fixed lattice of squares (cubes) from "
                      "`grid.min` over which J^e is averaged (1: cell-wise; read only with `fbar: modified`).",
           .default_text = "1 (linear, gimp), 1.5 (bspline2, bspline3)"},
      }};
  return t;
}

#pragma GCC diagnostic pop

std::vector<const Table*> all_tables() {
  return {&scene_table(),     &grid_table(),     &material_table(),  &solid_table(),
          &elastic_table(),   &strength_table(), &nor_sand_table(),  &fluid_table(),
          &body_table(),      &geometry_table(), &box_table(),       &polygon_table(),
          &slope_table(),     &footing_table(),  &gmsh_table(),      &surface_mesh_table(),
          &initial_table(),   &boundary_table(), &load_table(),      &region_table(),
          &time_table(),      &output_table(),   &monitor_table(),   &solver_table(),
          &stabilisation_table(), &air_table(),   &phase_field_table(), &initialisation_table()};
}

std::vector<const Table*> model_tables(MaterialModel m) {
  switch (m) {
    case MaterialModel::linear_elastic:
    case MaterialModel::hencky: return {&solid_table(), &elastic_table()};
    case MaterialModel::mohr_coulomb:
    case MaterialModel::drucker_prager: return {&solid_table(), &elastic_table(), &strength_table()};
    case MaterialModel::nor_sand: return {&solid_table(), &nor_sand_table()};
    case MaterialModel::fluid: return {&fluid_table()};
  }
  return {};
}

std::vector<const Table*> constitutive_tables(MaterialModel m) {
  switch (m) {
    case MaterialModel::linear_elastic:
    case MaterialModel::hencky: return {&elastic_table()};
    case MaterialModel::mohr_coulomb:
    case MaterialModel::drucker_prager: return {&elastic_table(), &strength_table()};
    case MaterialModel::nor_sand: return {&nor_sand_table()};
    case MaterialModel::fluid: return {};
  }
  return {};
}

}  // namespace swmpm::scene::detail

namespace swmpm::scene {

using namespace detail;

// ------------------------------------------------------------------------------------------------
// Grid faces and the named surfaces of geometries (scene.hpp).
// ------------------------------------------------------------------------------------------------

int grid_face_index(const std::string& name) {
  const auto& faces = face_names();
  const auto it = std::find(faces.begin(), faces.end(), name);
  return it == faces.end() ? -1 : static_cast<int>(it - faces.begin());
}

std::vector<std::string> named_surfaces(const Geometry& g, int dimension) {
  if (g.type == "slope") return {"surface", "base", "left", "right", "toe", "slope_face", "crest"};
  if (g.type == "footing") {
    if (dimension == 3) return {"bottom", "top", "left", "right", "back", "front"};
    return {"bottom", "top", "left", "right"};
  }
  return {};
}

std::vector<std::string> surface_bit_names(const Scene& s) {
  std::vector<std::string> names;
  auto note = [&](const std::string& n) {
    if (!contains(face_names(), n) && !contains(names, n)) names.push_back(n);
  };
  for (const Boundary& b : s.boundaries) note(b.on);
  for (const Load& l : s.loads) note(l.face);
  return names;
}

}  // namespace swmpm::scene
