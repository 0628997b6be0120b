// The formulation table (scene/formulations.hpp): one row per formulation, read by the parser,
// preprocess, the loop and the registry. Checked here: every implemented row has a solver and
// only those; the switch checks name the path, what the formulation has and who reads a switch;
// the defaults by formulation; the semi-implicit rows' own checks.
#include <gtest/gtest.h>

#include "scene/formulations.hpp"
#include "solver/formulation.hpp"

using swmpm::has_solver;
using swmpm::scene::Body;
using swmpm::scene::Boundary;
using swmpm::scene::FluidBc;
using swmpm::scene::Formulation;
using swmpm::scene::FormulationRow;
using swmpm::scene::Problem;
using swmpm::scene::Scene;
using swmpm::scene::ShapeFunction;
using namespace swmpm::scene;
using nlohmann::json;

namespace {

Scene scene_of(Formulation f) {
  Scene s;
  s.formulation = f;
  s.grid.shape_function = ShapeFunction::gimp;
  s.solver.stabilisation.pressure = "";  // unset, as the parser leaves a file without the key
  Body b;
  b.name = "column";
  b.particles_per_cell = 1;
  s.bodies.push_back(b);
  return s;
}

bool has_problem(const std::vector<Problem>& ps, const std::string& path, const std::string& text) {
  for (const auto& p : ps)
    if (p.path == path && p.message.find(text) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST(FormulationTable, ImplementedRowsAreExactlyThoseWithASolver) {
  int implemented = 0;
  for (const FormulationRow& r : formulation_rows()) {
    EXPECT_EQ(r.implemented, has_solver(r.id)) << r.name;
    EXPECT_EQ(row_of(r.id).name, to_string(r.id));
    implemented += r.implemented;
    // A row keeps its water in one place.
    EXPECT_FALSE(r.water.pore_fluid_on_solid && r.water.fluid_particles) << r.name;
    EXPECT_EQ(r.coupled, r.id != Formulation::dry) << r.name;
  }
  EXPECT_EQ(implemented, 6);
  EXPECT_EQ(implemented_formulations(),
            "dry, explicit-single-point, semi-implicit-single-point, semi-implicit-double-point, explicit-double-point, "
            "mpm-fem");
  EXPECT_THROW(row_of(Formulation::automatic), std::logic_error);
}

TEST(FormulationTable, SwitchesAreCheckedAgainstTheRow) {
  // A value the formulation lacks: the path and the row's own values.
  Scene esp = scene_of(Formulation::explicit_single_point);
  auto p = check_formulation(json::parse(R"({"solver": {"stabilisation": {"pressure": "node-remap"}}})"), esp);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_TRUE(has_problem(p, "/solver/stabilisation/pressure",
                          "explicit-single-point does not have; expected one of none, mfvp-constant, mfvp-linear, "
                          "mfvp-quadratic, cell-constant"));
  // A switch the formulation does not read: who reads it.
  Scene dry = scene_of(Formulation::dry);
  p = check_formulation(json::parse(R"({"solver": {"stabilisation": {"strain_smoothing": false}, "continuity": "conservative"}})"), dry);
  EXPECT_TRUE(has_problem(p, "/solver/stabilisation/strain_smoothing", "dry does not read this switch (read by explicit-single-point)"));
  EXPECT_TRUE(has_problem(p, "/solver/continuity", "read by explicit-single-point, semi-implicit-single-point, semi-implicit-double-point"));
  Scene sp = scene_of(Formulation::semi_implicit_single_point);
  p = check_formulation(json::parse(R"({"solver": {"escaped_water": "remove"}, "initialisation": {"tie_water": true}})"), sp);
  EXPECT_TRUE(has_problem(p, "/solver/escaped_water", "read by semi-implicit-double-point"));
  EXPECT_TRUE(has_problem(p, "/initialisation/tie_water", "read by semi-implicit-double-point, explicit-double-point"));
  // What the row has passes; a type error is the schema's to report.
  Scene dp = scene_of(Formulation::semi_implicit_double_point);
  p = check_formulation(json::parse(R"({"solver": {"escaped_water": "remove", "continuity": 3,
      "drag_integration": "semi-implicit", "stabilisation": {"pressure": "node-remap"}}})"), dp);
  EXPECT_TRUE(p.empty()) << p[0].path << ": " << p[0].message;
}

TEST(FormulationTable, SemiImplicitRowsRefuseOnePointPerCellWithBSplinesAndPressureOnNamedSurfaces) {
  for (const Formulation f : {Formulation::semi_implicit_single_point, Formulation::semi_implicit_double_point}) {
    Scene s = scene_of(f);
    EXPECT_TRUE(check_formulation(json::object(), s).empty());  // gimp: one point per cell is fine
    s.grid.shape_function = ShapeFunction::bspline2;
    Boundary b;
    b.on = "slope_face";
    b.fluid = FluidBc::pressure;
    s.boundaries.push_back(b);
    const auto p = check_formulation(json::object(), s);
    EXPECT_TRUE(has_problem(p, "/bodies/0/particles_per_cell", "not available with bspline2"));
    EXPECT_TRUE(has_problem(p, "/boundaries/0/fluid", "named surface (\"slope_face\") is not implemented"));
  }
  Scene esp = scene_of(Formulation::explicit_single_point);  // not a semi-implicit limit
  esp.grid.shape_function = ShapeFunction::bspline2;
  EXPECT_TRUE(check_formulation(json::object(), esp).empty());
}

TEST(FormulationTable, DefaultsByFormulation) {
  Scene si = scene_of(Formulation::semi_implicit_double_point);
  apply_formulation_defaults(si);
  EXPECT_EQ(si.solver.stabilisation.pressure, "mfvp-linear");
  EXPECT_EQ(si.solver.continuity, "conservative");
  EXPECT_EQ(si.solver.drag_integration, "implicit");
  Scene esp = scene_of(Formulation::explicit_single_point);
  esp.solver.continuity = "conservative";  // set by the file: kept
  apply_formulation_defaults(esp);
  EXPECT_EQ(esp.solver.stabilisation.pressure, "mfvp-linear");
  EXPECT_EQ(esp.solver.continuity, "conservative");
  EXPECT_EQ(esp.solver.drag_integration, "");
  Scene dry = scene_of(Formulation::dry);
  apply_formulation_defaults(dry);
  EXPECT_EQ(dry.solver.stabilisation.pressure, "none");
  EXPECT_EQ(dry.solver.continuity, "non-conservative");
}
