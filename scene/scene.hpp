// The scene model: the typed contract between the stages (interface.md §2).
//
// A scene file is parsed and validated once (scene/parse.cpp) into these structs; physics code
// receives them as const& and never reads JSON. SI units throughout. Every default and range lives
// in the schema tables in keys.cpp and is documented in docs/scene-format.md.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace swmpm::scene {

enum class Formulation {
  dry,
  explicit_single_point,
  semi_implicit_single_point,
  semi_implicit_double_point,
  explicit_double_point,
  mpm_fem,
  automatic  // "auto": resolved by the parser (see resolve_formulation)
};

enum class ShapeFunction { linear, gimp, bspline2, bspline3 };

enum class MaterialModel { linear_elastic, hencky, mohr_coulomb, drucker_prager, nor_sand, fluid };

enum class SolidBc { fixed, roller, free, friction };
enum class FluidBc { impermeable, drained, pressure };

/// Up to three components; only the first `dimension` are meaningful.
using Vec3 = std::array<double, 3>;

/// A scalar function of time, f(t): constant 1 unless an expression or a table is given,
/// multiplied by a linear ramp from 0 to 1 over `ramp` seconds when ramp > 0.
struct TimeFunction {
  double ramp = 0.0;                          // s
  std::string expression;                     // muParser expression in t (empty: none)
  std::vector<std::array<double, 2>> table;   // (t, value) pairs, piecewise linear, clamped
};

struct Grid {
  double cell_size = 0.0;       // m
  Vec3 min{0, 0, 0};            // m
  Vec3 max{0, 0, 0};            // m
  ShapeFunction shape_function = ShapeFunction::gimp;
};

struct Material {
  std::string name;
  MaterialModel model = MaterialModel::linear_elastic;
  /// Every model parameter by its full scene name (youngs_modulus, poisson_ratio, density,
  /// grain_density, porosity, cohesion, friction_angle, ...), validated against the model's
  /// parameter table and with defaults filled in. Units as in docs/scene-format.md.
  std::map<std::string, double> params;
  std::string permeability_law = "constant";  // "constant" | "kozeny-carman" | "xie-leo"

  bool has(const std::string& key) const { return params.count(key) != 0; }
  double at(const std::string& key) const;  // throws std::out_of_range naming the key
  /// Density of the solid skeleton in the mixture [kg/m^3]: density, or (1-n) grain_density.
  double solid_bulk_density() const;
};

struct Geometry {
  std::string type;             // box | polygon | slope | gmsh | surface-mesh | footing
  Vec3 min{0, 0, 0}, max{0, 0, 0};            // box [m]
  std::vector<std::array<double, 2>> vertices;  // polygon (2D), counter-clockwise or clockwise
  nlohmann::json raw;           // the geometry object as written, for types that need more keys

  // gmsh, surface-mesh: the file, resolved against the scene file's folder (absolute path).
  std::string file;
  std::map<std::string, double> parameters;  // gmsh .geo: DefineConstant overrides
  std::string physical;  // gmsh: physical group (surface in 2D, volume in 3D) forming the body; "" = all

  // slope (2D): foundation toe -> slope face -> crest, see docs/scene-format.md.
  double foundation_depth = 0.0;  // m
  double height = 0.0;            // m: slope height (slope), block height (footing)
  double angle = 0.0;             // deg from horizontal; 0 when `ratio` is given
  double ratio = 0.0;             // horizontal : vertical; 0 when `angle` is given
  double crest_length = 0.0;      // m
  double toe_length = 0.0;        // m
  std::array<double, 2> origin{0.0, 0.0};  // m, lower-left corner of the foundation

  // footing: a block centred on x (and z in 3D) standing on base_y.
  double width = 0.0;      // m, along x
  double length = 0.0;     // m, along z (3D)
  double center_x = 0.0;   // m
  double center_z = 0.0;   // m (3D)
  double base_y = 0.0;     // m, resolved from `on` (the top of that body) when given
};

/// The named surfaces a geometry defines by its type (slope, footing), in the order documented in
/// docs/scene-format.md. Empty for box, polygon and surface-mesh, and for gmsh, whose names (the
/// physical groups) are known only once preprocess reads the file.
std::vector<std::string> named_surfaces(const Geometry& g, int dimension);

struct InitialState {
  std::optional<double> pore_pressure;  // Pa, compression positive
  bool hydrostatic = false;             // pore_pressure: "hydrostatic"
  std::optional<double> water_table;    // m (height), with hydrostatic
  bool geostatic = false;               // stress: "geostatic"
  double k0 = 0.5;                      // lateral earth pressure coefficient, with geostatic
  std::optional<std::array<double, 6>> stress;  // Pa, tension positive, Voigt xx yy zz xy yz xz
  std::optional<double> porosity;       // overrides the material's
  /// Initial velocity: per component an expression in x, y, z (constants are expressions too).
  std::array<std::string, 3> velocity{"0", "0", "0"};  // m/s
};

struct Body {
  std::string name;
  Geometry geometry;
  std::string solid;  // material name, empty when the body has no solid
  std::string fluid;  // material name, empty when the body has no fluid
  int particles_per_cell = 2;  // per direction: n^dim particles per cell
  InitialState initial;
};

struct Boundary {
  std::string on;  // x_min .. z_max, or a named surface of a body's geometry
  SolidBc solid = SolidBc::free;
  double coefficient = 0.0;  // friction coefficient (solid == friction)
  std::optional<FluidBc> fluid;
  double fluid_value = 0.0;  // Pa, with fluid == pressure
};

struct Load {
  std::string type;   // traction | pressure
  std::string body;
  std::string face;   // x_min .. z_max: the body's surface layer facing that way; or a named surface
  Vec3 value{0, 0, 0};   // traction vector [Pa] (traction) or value[0] = pressure [Pa] (pressure)
  std::optional<std::pair<Vec3, Vec3>> region;  // limit to particles inside [min, max] at t = 0
  TimeFunction function;
};

struct Monitor {
  std::string name;
  std::optional<Vec3> at;        // nearest particle of `phase` at t = 0, followed through the run
  std::optional<long> particle;  // or a particle id
  // A water_level gauge instead (`at` and `particle` empty): its vertical line (x, ·, z) [m], y
  // unused (the file's "at": [x] in 2D, [x, z] in 3D; y is the vertical axis). monitors.hpp
  // defines the level it reads.
  std::optional<Vec3> gauge;
  std::string phase = "solid";   // solid | fluid
  std::string points = "soil";   // soil | water: which set a point monitor follows (water: double-point)
  std::vector<std::string> quantities;
};

struct Output {
  double interval = 0.0;          // s between VTU frames (0: first and last only)
  double monitor_interval = 0.0;  // s between monitor rows (0: every step)
  std::string compression = "zlib";  // VTU frames: zlib (level 1) | lz4 | none
  std::optional<double> checkpoint_interval;  // s between restart checkpoints on disk; empty: with every frame
  std::vector<Monitor> monitors;
};

struct Time {
  double end = 0.0;        // s
  std::optional<double> dt;  // s; empty = "auto"
  double cfl = 0.5;        // with dt "auto"
};

struct Stabilisation {
  bool strain_smoothing = true;
  std::string pressure = "none";  // none | mfvp-constant | mfvp-linear | mfvp-quadratic | node-remap
  std::string fbar = "none";      // none | standard | modified
  double fbar_patch = 0.0;        // -, h_patch / h of the modified F-bar (0: default_fbar_patch)
};

/// h_patch / h of the modified F-bar when the scene gives none (seed 001 §4.4.2 and step (9)(f)):
/// cell-wise (1) for linear and GIMP, patch-wise 1.5 for the B-splines.
double default_fbar_patch(ShapeFunction f);

/// mpm-fem (seed 004): the air of the fluid phase above the water's free surface, a second
/// Newtonian fluid on the grid mixed with the water by the phase field.
struct Air {
  double density = 1.2;              // kg/m^3
  double dynamic_viscosity = 1.8e-5;  // Pa s
  bool whole_grid = false;            // domain "grid": the fluid on every cell (else near water and soil)
};

/// mpm-fem (seed 004): the Allen–Cahn phase field phi (1 water, 0 air) that carries the water's
/// free surface on the grid. Absent values are the solver's to choose.
struct PhaseField {
  std::optional<double> interface_width;  // m, the interface's 5 %-95 % width; absent: the solver's (3 cells)
  std::optional<double> mobility;         // 1/s, M_phi W of seed 004's Allen–Cahn equation with the barrier
                                          // height W = 1: the interface's relaxation rate; absent: the solver's (200)
  bool lsic = false;               // the seed's LSIC diffusion (h/2)|v| in the phase field's equation
  bool volume_correction = true;   // int n phi restored after each step
};

struct Solver {
  double flip = 0.99;            // FLIP fraction of the FLIP/PIC blend (1 = pure FLIP)
  double damping = 0.0;          // local (Cundall) damping coefficient, 0..1
  std::string kinematics = "finite-strain";  // small-strain | finite-strain
  std::string continuity;  // non-conservative | conservative (mixture volume balance); "" = the formulation's
                           // default (conservative for semi-implicit), which parse resolves
  // Double-point water points that have left the soil (outside its volume, past a drained free
  // surface): keep | remove (an outflow into an unmodelled reservoir; docs/formulations.md)
  std::string escaped_water = "keep";
  // Semi-implicit formulations: the drag of the predictor implicit in the water velocity only
  // (semi-implicit, seed 001 eqs. 52-53) or in both phases' velocities (implicit, the default).
  std::string drag_integration;  // "" until parse resolves it by formulation
  std::string drag;  // explicit-double-point: darcy | ergun ("" until parse resolves it by formulation)
  Stabilisation stabilisation;
  int checkpoint_every = 50;     // steps between in-memory snapshots of the last good state
  Air air;                       // mpm-fem: the gas above the water's free surface
  PhaseField phase_field;        // mpm-fem: the Allen–Cahn phase field phi (1 water, 0 air)
  int soil_substeps = 1;         // mpm-fem: soil steps per step of the fluid and the phase field
};

/// An initialisation phase before the analysis (seed 001 App. B.4): t runs from -duration to 0
/// under gravity ramped from zero, with plasticity off, a high permeability and (double-point)
/// the water points tied to their soil points, so that the analysis starts at t = 0 from an
/// equilibrium state with dissipated pore pressures.
struct Initialisation {
  double duration = 0.0;      // s; 0: no initialisation phase
  double gravity_ramp = 0.0;  // s from the start of the phase (<= duration)
  bool plasticity = false;    // plastic flow allowed during the phase
  std::optional<double> hydraulic_conductivity;  // m/s for every porous material during the phase
  bool tie_water = true;      // double-point: water points follow their coincident soil points
  std::optional<double> damping;  // local damping during the phase (default solver.damping)
  bool reset_displacement = true;  // displacements are measured from the state at t = 0
  /// Material parameters in place of the scene's while the phase runs (seed 004: a large cohesion
  /// while gravity grows, c = 0 from t = 0): material name -> parameter name -> value, only the
  /// parameters of the material's constitutive model (units as in the material tables).
  std::map<std::string, std::map<std::string, double>> materials;
  bool enabled() const { return duration > 0.0; }
};

struct Scene {
  std::string name;
  int dimension = 2;
  Formulation formulation = Formulation::dry;
  std::string formulation_reason;  // why "auto" picked what it picked
  /// How "auto" chose (scene/auto_formulation.hpp, to_json): {"chosen", "automatic", "rule",
  /// "reason", "estimates"}; null when the scene file named its formulation. The resolved
  /// scene.json carries it, so that solve can log it and write it to run.json.
  nlohmann::json formulation_choice;
  Vec3 gravity{0, 0, 0};           // m/s^2
  double gravity_ramp = 0.0;       // s
  Grid grid;
  std::vector<Material> materials;
  std::vector<Body> bodies;
  std::vector<Boundary> boundaries;
  std::vector<Load> loads;
  Time time;
  Output output;
  Solver solver;
  Initialisation initialisation;
  std::string source_file;  // path of the scene file (for relative paths and messages)
  bool trust_geometry = false;  // --trust-geometry: mesh .geo scripts unchecked (not a scene key)
  double max_memory = 0.0;      // B, --max-memory (0: the machine's memory; not a scene key)

  const Material& material(const std::string& name) const;
  int material_index(const std::string& name) const;
  bool has_fluid() const;
};

/// All validation problems of one scene file, one line each:
/// "scene.json: /materials/1/poisson_ratio: got 0.7, expected a number in [0, 0.5) [-]".
class SceneError : public std::runtime_error {
 public:
  explicit SceneError(std::vector<std::string> lines);
  const std::vector<std::string>& lines() const { return lines_; }

 private:
  std::vector<std::string> lines_;
};

/// Parse and validate a scene file. Throws SceneError listing every problem found.
Scene load_scene(const std::string& path);
/// Same, from a JSON value; `label` names the source in messages.
Scene parse_scene(const nlohmann::json& j, const std::string& label);
/// The scene with every default filled in, as JSON that parse_scene (and `swmpm preprocess`)
/// accepts again. Switches the scene's formulation does not read are left out (see
/// reads_switch), since preprocess rejects them when a file sets them.
nlohmann::json to_json(const Scene& s);

/// Whether the scene's formulation reads the solver switch `key` ("strain_smoothing",
/// "pressure", "fbar_patch", "kinematics"; any other key: true). One rule for to_json and for
/// preprocess's rejection of switches a scene sets in vain.
bool reads_switch(const Scene& s, const std::string& key);

/// Particle face bits: bits 0-5 are the axis faces (2 axis + side); bit kFirstSurfaceBit + k is the
/// k-th entry of surface_bit_names(), the distinct named surfaces the scene refers to.
constexpr int kFirstSurfaceBit = 6;
constexpr int kMaxNamedSurfaces = 32 - kFirstSurfaceBit;  // 26
/// The named surfaces (not x_min .. z_max) that `boundaries[].on` and then `loads[].face` refer
/// to, each once, in order of first mention: the one place both preprocess (tagging) and the
/// solver (loads) learn which face bit a name has.
std::vector<std::string> surface_bit_names(const Scene& s);

/// Index 2 axis + side of a grid face ("x_min" 0, "x_max" 1, ... "z_max" 5); -1 for any other
/// name (a named surface: a gmsh physical group).
int grid_face_index(const std::string& name);
std::string to_string(Formulation f);
std::string to_string(ShapeFunction f);
std::string to_string(MaterialModel m);

/// Every key name declared in the scene schema tables (keys.cpp), sorted, without duplicates.
std::vector<std::string> schema_keys();
/// The schema tables as Markdown (one table per object kind: key, type, unit, default, allowed,
/// meaning); docs/scene-format.md contains them verbatim (checked by a unit test).
std::string schema_markdown();

}  // namespace swmpm::scene
