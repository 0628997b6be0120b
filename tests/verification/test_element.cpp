// `swmpm element`: one material point driven by deformation-gradient increments through the
// solver's material models (solver/element.cpp).
//  (1) linear-elastic oedometer: axial stress increment M ε, M = E(1−ν)/((1+ν)(1−2ν)); lateral
//      increment ν/(1−ν) times the axial one;
//  (2) mohr-coulomb (c = 0, φ = 30°) drained triaxial from p0 = 100 kPa: the lateral stress stays
//      p0, Δq = 3Δp all along, and q/p′ ends at M_c = 6 sin φ/(3 − sin φ) = 1.2;
//  (3) linear-elastic undrained (isochoric) triaxial: ε_v = 0 and p′ constant (Δp = K ε_v = 0);
//  (4) the command line: a wrong material name, a fluid material, the CSV header.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "scene/scene.hpp"
#include "solver/element.hpp"
#include "support/run_helpers.hpp"

namespace {

using nlohmann::json;

constexpr double E = 1e8, nu = 0.3, p0 = 100e3;

json element_scene() {
  return {
      {"name", "element"},
      {"dimension", 3},
      {"formulation", "dry"},
      {"gravity", {0.0, 0.0, 0.0}},
      {"grid", {{"cell_size", 0.1}, {"min", {0.0, 0.0, 0.0}}, {"max", {0.4, 0.4, 0.4}}, {"shape_function", "gimp"}}},
      {"materials",
       {{{"name", "clay"}, {"model", "linear-elastic"}, {"density", 2000.0}, {"youngs_modulus", E},
         {"poisson_ratio", nu}},
        {{"name", "sand"}, {"model", "mohr-coulomb"}, {"density", 2000.0}, {"youngs_modulus", E},
         {"poisson_ratio", nu}, {"cohesion", 0.0}, {"friction_angle", 30.0}, {"dilation_angle", 0.0}}}},
      {"bodies",
       {{{"name", "sample"},
         {"geometry", {{"type", "box"}, {"min", {0.0, 0.0, 0.0}}, {"max", {0.2, 0.2, 0.2}}}},
         {"solid", "sand"},
         {"particles_per_cell", 2}}}},
      {"time", {{"end", 0.1}, {"dt", 1e-4}}},
      {"output", {{"interval", 0.0}}}};
}

swmpm::scene::Scene scene() { return swmpm::scene::parse_scene(element_scene(), "element-scene"); }

TEST(Element, LinearElasticOedometer) {
  const double eps = 1e-4;
  const auto r = swmpm::run_element(scene(), "clay", swmpm::ElementTest::oedometer, p0, eps, 10);
  const double M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu));
  const double da = r.axial_stress.back() - p0, dr = r.radial_stress.back() - p0;
  std::printf("oedometer: d sigma_a / (M eps) = %.8f, d sigma_r / d sigma_a = %.8f (nu/(1-nu) = %.8f)\n",
              da / (M * eps), dr / da, nu / (1 - nu));
  EXPECT_NEAR(da / (M * eps), 1.0, 1e-3);
  EXPECT_NEAR(dr / da, nu / (1 - nu), 1e-3);
  EXPECT_NEAR(r.volumetric_strain.back(), eps, 1e-12);
  EXPECT_EQ(r.size(), 11u);
}

TEST(Element, MohrCoulombDrainedTriaxial) {
  const auto r = swmpm::run_element(scene(), "sand", swmpm::ElementTest::drained_triaxial, p0, 0.05, 200);
  const double s = std::sin(30.0 * M_PI / 180.0), Mc = 6 * s / (3 - s);
  double worst_radial = 0.0, worst_slope = 0.0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    worst_radial = std::max(worst_radial, std::abs(r.radial_stress[i] - p0) / p0);
    worst_slope = std::max(worst_slope, std::abs(r.q[i] - 3.0 * (r.p[i] - p0)) / p0);
  }
  const double eta = r.q.back() / r.p.back();
  std::printf("drained MC: q/p' end = %.8f (M_c = %.8f), max |sigma_r - p0|/p0 = %.2e, max |q - 3 dp|/p0 = %.2e, "
              "eps_v end = %.5f\n", eta, Mc, worst_radial, worst_slope, r.volumetric_strain.back());
  EXPECT_NEAR(eta / Mc, 1.0, 0.01);
  EXPECT_LT(worst_radial, 1e-8);
  EXPECT_LT(worst_slope, 1e-8);
  // Dilation angle 0: past failure the volume stops changing.
  const std::size_t n = r.size();
  EXPECT_NEAR(r.volumetric_strain[n - 1], r.volumetric_strain[n - 2], 1e-9);
}

TEST(Element, LinearElasticUndrainedTriaxial) {
  const auto r = swmpm::run_element(scene(), "clay", swmpm::ElementTest::undrained_triaxial, p0, 0.01, 50);
  double worst_ev = 0.0, worst_p = 0.0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    worst_ev = std::max(worst_ev, std::abs(r.volumetric_strain[i]));
    worst_p = std::max(worst_p, std::abs(r.p[i] - p0) / p0);
  }
  std::printf("undrained LE: max |eps_v| = %.2e, max |p - p0|/p0 = %.2e, q end = %.1f Pa\n", worst_ev, worst_p,
              r.q.back());
  EXPECT_LT(worst_ev, 1e-12);
  EXPECT_LT(worst_p, 1e-6);
  EXPECT_GT(r.q.back(), 0.0);
}

TEST(Element, CommandLine) {
  const auto dir = swmpm::testing::scratch("element-cli");
  const auto scene_file = (dir / "scene.json").string();
  json s = element_scene();
  s["materials"].push_back({{"name", "water"}, {"model", "fluid"}, {"density", 1000.0}, {"bulk_modulus", 2.2e9},
                            {"dynamic_viscosity", 1e-3}});
  std::ofstream(scene_file) << s.dump(2);

  auto r = swmpm::testing::swmpm_cmd("element " + scene_file + " --material nosuch --test oedometer --p0 1e5 "
                                     "--axial-strain 0.01", dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("nosuch"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("clay"), std::string::npos) << r.err;

  r = swmpm::testing::swmpm_cmd("element " + scene_file + " --material water --test oedometer --p0 1e5 "
                                "--axial-strain 0.01", dir);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("fluid"), std::string::npos) << r.err;

  const auto csv = (dir / "out.csv").string();
  r = swmpm::testing::swmpm_cmd("element " + scene_file + " --material sand --test drained-triaxial --p0 1e5 "
                                "--axial-strain 0.02 --steps 20 --out " + csv, dir);
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream in(csv);
  std::string line, header;
  int rows = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header.empty()) header = line;
    else ++rows;
  }
  EXPECT_EQ(header, "axial_strain,p,q,volumetric_strain");
  EXPECT_EQ(rows, 21);
}

}  // namespace
