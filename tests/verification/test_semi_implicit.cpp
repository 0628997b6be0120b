// Semi-implicit formulations (seed 001): B1 Terzaghi for both variants, E1 hydrostatic layer at
// rest for both variants, and the pressure stabilisation switch measured on both.
//
// B1 (seed 001 §5.1, Table 1): column 0.1 x 1.0 m, cells 0.025 m, 2x2 points per cell (640 per
// phase), E = 10 MPa, nu = 0, rho_s = 2650, rho_w = 1000, n0 = 0.3, k = 1e-3 m/s, no gravity;
// sides and base roller/fixed and impermeable, top free and drained; q = 10 kPa applied at t = 0
// and held; dt = 1e-4 s. Incompressible constituents: the undrained response is p = q at once and
// c_v = k E_oed / gamma_w. Terzaghi (drained top, z depth below the top; seed-notes item 4):
//   p / q = sum_m (2/M) sin(M z / H) exp(-M^2 Tv),  M = (2m + 1) pi / 2,  Tv = c_v t / H^2.
#include <gtest/gtest.h>

#include <cmath>

#include "scene/scene.hpp"
#include "solver/grid/grid.hpp"
#include "solver/shape/shape.hpp"
#include "support/indicators.hpp"
#include "support/run_helpers.hpp"

namespace {

using nlohmann::json;

constexpr double H = 1.0, q = 1.0e4, E = 1.0e7, k = 1.0e-3, rho_w = 1000.0, g = 9.81;

double terzaghi(double z, double Tv) {
  double sum = 0.0;
  for (int m = 0; m < 200; ++m) {
    const double M = (2 * m + 1) * M_PI / 2;
    sum += 2.0 / M * std::sin(M * z / H) * std::exp(-M * M * Tv);
  }
  return sum;
}

struct Profiles {
  double worst_rms = 0.0, first_rms = 0.0, last_rms = 0.0;
  int frames = 0;
  double base_at_end = 0.0;  // Pa, pore pressure of the monitor at the base at the last frame
};

/// Runs B1 with `formulation` and `pressure` stabilisation to `end`; RMS error of p/q over every
/// frame from t = 0.05 s.
Profiles run_b1(const std::string& formulation, const std::string& pressure, double end, const std::string& name,
                const std::string& shape = "gimp") {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi-semi-implicit/scene.json");
  s["formulation"] = formulation;
  s["grid"]["shape_function"] = shape;
  s["solver"]["stabilisation"]["pressure"] = pressure;
  s["time"]["end"] = end;
  const std::string run = swmpm::testing::run_scene(s, name);
  const double c_v = k * E / (rho_w * g);  // nu = 0: E_oed = E; incompressible water and grains
  Profiles r;
  for (const auto& e : swmpm::scene::read_pvd(run + "/output/results.pvd")) {
    if (e.group != "solid" || e.time < 0.049) continue;
    const auto f = swmpm::scene::read_vtu(run + "/output/" + e.file);
    const auto& pp = f.get("pore_pressure", e.file).values;
    const auto& d = f.get("displacement", e.file).values;
    const double Tv = c_v * e.time / (H * H);
    double err2 = 0.0;
    for (std::size_t p = 0; p < f.size(); ++p) {
      const double z = H - (f.points[p][1] - d[3 * p + 1]);
      err2 += std::pow(pp[p] / q - terzaghi(z, Tv), 2);
    }
    const double rms = std::sqrt(err2 / static_cast<double>(f.size()));
    if (r.frames == 0) r.first_rms = rms;
    r.last_rms = rms;
    r.worst_rms = std::max(r.worst_rms, rms);
    ++r.frames;
  }
  std::printf("B1 %s, %s, %s: %d frames, RMS error of p/q: first %.4f, worst %.4f, last %.4f\n", formulation.c_str(),
              shape.c_str(), pressure.c_str(), r.frames, r.first_rms, r.worst_rms, r.last_rms);
  return r;
}

}  // namespace

// Measured (cells 0.025, dt 1e-4, to 0.5 s, GIMP): single-point worst RMS 0.12 % (at Tv = 0.05),
// double-point 0.30 %. The tolerance is issue 4's 3 % bound tightened to 0.5 %.
TEST(SemiImplicit, B1TerzaghiSinglePoint) {
  const Profiles r = run_b1("semi-implicit-single-point", "mfvp-linear", 0.5, "b1-sp");
  EXPECT_GE(r.frames, 9);
  EXPECT_LT(r.worst_rms, 0.005);
}

TEST(SemiImplicit, B1TerzaghiDoublePoint) {
  const Profiles r = run_b1("semi-implicit-double-point", "mfvp-linear", 0.5, "b1-dp");
  EXPECT_GE(r.frames, 9);
  EXPECT_LT(r.worst_rms, 0.005);
}

// B-splines (the paper's shape functions): the free surface lies between nodes, so its nodes take
// the linear fit shifted to vanish on the surface, and the pressure force and corrections use the
// strong gradient (docs/formulations.md, "B-splines in the semi-implicit formulations").
// Measured worst RMS to 0.5 s: bspline2 0.10 % (single-point), 0.21 % (double-point); bspline3
// 0.08 % / 0.16 %. Before the fix both diverged within 10 steps.
TEST(SemiImplicit, B1TerzaghiBspline2SinglePoint) {
  const Profiles r = run_b1("semi-implicit-single-point", "mfvp-linear", 0.5, "b1-sp-b2", "bspline2");
  EXPECT_GE(r.frames, 9);
  EXPECT_LT(r.worst_rms, 0.005);
}

TEST(SemiImplicit, B1TerzaghiBspline2DoublePoint) {
  const Profiles r = run_b1("semi-implicit-double-point", "mfvp-linear", 0.5, "b1-dp-b2", "bspline2");
  EXPECT_GE(r.frames, 9);
  EXPECT_LT(r.worst_rms, 0.005);
}

// Double-point water points take their porosity and volume in the P2G of each step, from that
// step's nodal porosity (docs/formulations.md, "Water points' porosity"); a frame fills them where
// the points are when it is written. Checked against the same sums done here from the frame
// itself: the soil's porosity mapped with its mass, n_I = sum S m n / sum S m (1 without soil),
// interpolated at each water point, V = m / (n rho_w). Measured: porosity within 1.1e-16, volume
// 3.5e-16 relative. B1 consolidates, so the porosity changes every step: the values of the last
// step's start (the frame without the completion) differ by 3.4e-6 (volume 1.2e-5).
TEST(SemiImplicit, DoublePointFrameHoldsWaterPorosityWhereThePointsAre) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi-semi-implicit/scene.json");
  s["formulation"] = "semi-implicit-double-point";
  s["grid"]["shape_function"] = "bspline2";
  s["time"]["end"] = 0.01;
  s["output"]["interval"] = 0.005;
  const std::string run = swmpm::testing::run_scene(s, "b1-dp-water-porosity");
  const auto soil = swmpm::testing::last_frame(run), water = swmpm::testing::last_frame(run, "fluid");
  const swmpm::Grid<2> grid(swmpm::Vec<2>(0.0, 0.0), swmpm::Vec<2>(0.1, 1.1), 0.025, 2, true);
  using Shape = swmpm::shape::BSpline<2>;
  auto weights = [&](const std::array<double, 3>& x) {
    swmpm::shape::ShapeData<2, Shape::support, false> sd;
    swmpm::shape::evaluate<Shape>(grid, swmpm::Vec<2>(x[0], x[1]), swmpm::Vec<2>(swmpm::Vec<2>::Zero()), sd);
    return sd;
  };
  std::vector<double> m_node(grid.num_nodes(), 0.0), mn_node(grid.num_nodes(), 0.0);
  const auto& ms = soil.get("mass", "solid").values;
  const auto& ns = soil.get("porosity", "solid").values;
  for (std::size_t p = 0; p < soil.size(); ++p)
    swmpm::shape::for_each_node(grid, weights(soil.points[p]), [&](std::size_t i, double N, const auto&) {
      m_node[i] += N * ms[p];
      mn_node[i] += N * ms[p] * ns[p];
    });
  const auto& mw = water.get("mass", "fluid").values;
  const auto& nw = water.get("porosity", "fluid").values;
  const auto& Vw = water.get("volume", "fluid").values;
  double worst_n = 0.0, worst_V = 0.0, spread = 0.0;
  for (std::size_t p = 0; p < water.size(); ++p) {
    double n = 0.0;
    swmpm::shape::for_each_node(grid, weights(water.points[p]), [&](std::size_t i, double N, const auto&) {
      n += N * (m_node[i] > 1e-14 ? mn_node[i] / m_node[i] : 1.0);
    });
    worst_n = std::max(worst_n, std::abs(nw[p] - n));
    worst_V = std::max(worst_V, std::abs(Vw[p] - mw[p] / (n * rho_w)) / Vw[p]);
    spread = std::max(spread, std::abs(nw[p] - 0.3));
  }
  std::printf("water points at t = 0.01 s: porosity within %.3g of the frame's soil mapped to them (volume %.3g "
              "relative); largest change from n0 %.3g\n",
              worst_n, worst_V, spread);
  EXPECT_GT(spread, 1e-5);  // the porosity has moved
  EXPECT_LT(worst_n, 1e-13);
  EXPECT_LT(worst_V, 1e-12);
}

TEST(SemiImplicit, B1TerzaghiBspline3BothVariants) {
  for (const std::string f : {"semi-implicit-single-point", "semi-implicit-double-point"}) {
    const Profiles r = run_b1(f, "mfvp-linear", 0.5, "b1-b3-" + f, "bspline3");
    EXPECT_GE(r.frames, 9) << f;
    EXPECT_LT(r.worst_rms, 0.005) << f;
  }
}

// The paper's node-wise map/remap (eq. 77, constant basis) is stable too, but biases the nodes of
// the drained top towards the interior: measured 0.19 % RMS at the first frame against 0.14 % with
// the linear basis (0.24 % with the seed's semi-implicit drag), converging as the gradient at the
// top flattens.
TEST(SemiImplicit, B1TerzaghiNodeRemapIsLessAccurate) {
  const Profiles remap = run_b1("semi-implicit-single-point", "node-remap", 0.2, "b1-remap");
  const Profiles linear = run_b1("semi-implicit-single-point", "mfvp-linear", 0.2, "b1-remap-linear");
  EXPECT_LT(remap.worst_rms, 0.03);
  EXPECT_GT(remap.first_rms, 1.25 * linear.first_rms);  // the bias is real (measured 1.36x)
}

namespace {

struct Rest {
  double p_max = 0.0, v_s = 0.0, v_w = 0.0;
};

/// E1 (the hydrostatic-layer example, 2 m of saturated soil under gravity, geostatic K0 stress,
/// hydrostatic pore pressure) to 0.3 s with `formulation`: largest pressure error (of rho_w g H)
/// and speeds over all frames of the soil points.
Rest run_e1(const std::string& formulation, const std::string& pressure, const std::string& name,
            const std::string& shape = "gimp") {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/hydrostatic-layer/scene.json");
  s["formulation"] = formulation;
  s["grid"]["shape_function"] = shape;
  s["solver"]["stabilisation"] = {{"pressure", pressure}};
  const std::string run = swmpm::testing::run_scene(s, name, 1);
  const double Hl = 2.0;
  Rest r;
  for (const auto& e : swmpm::scene::read_pvd(run + "/output/results.pvd")) {
    if (e.group != "solid") continue;
    const auto f = swmpm::scene::read_vtu(run + "/output/" + e.file);
    const auto& pp = f.get("pore_pressure", e.file).values;
    const auto& u = f.get("displacement", e.file).values;
    const auto& vs = f.get("velocity", e.file).values;
    const auto& vf = f.get("fluid_velocity", e.file).values;
    for (std::size_t p = 0; p < f.size(); ++p) {
      const double depth = Hl - (f.points[p][1] - u[3 * p + 1]);
      r.p_max = std::max(r.p_max, std::abs(pp[p] - rho_w * g * depth) / (rho_w * g * Hl));
      r.v_s = std::max(r.v_s, std::hypot(vs[3 * p], vs[3 * p + 1]));
      r.v_w = std::max(r.v_w, std::hypot(vf[3 * p], vf[3 * p + 1]));
    }
  }
  std::printf("E1 %s, %s, %s: p error max %.3g (of rho_w g H), max |v_s| %.3g m/s, max |v_w| %.3g m/s\n",
              formulation.c_str(), shape.c_str(), pressure.c_str(), r.p_max, r.v_s, r.v_w);
  return r;
}

}  // namespace

// The linear nodal projection reproduces the hydrostatic field at every node, the free-surface
// nodes included, so the layer stays at rest to round-off (measured: p 5e-17, speeds 1e-16 m/s).
TEST(SemiImplicit, E1HydrostaticLayerStaysAtRestSinglePoint) {
  const Rest r = run_e1("semi-implicit-single-point", "mfvp-linear", "e1-si-sp");
  EXPECT_LT(r.p_max, 1e-9);
  EXPECT_LT(r.v_s, 1e-12);
  EXPECT_LT(r.v_w, 1e-12);
}

TEST(SemiImplicit, E1HydrostaticLayerStaysAtRestDoublePoint) {
  const Rest r = run_e1("semi-implicit-double-point", "mfvp-linear", "e1-si-dp");
  EXPECT_LT(r.p_max, 1e-9);
  EXPECT_LT(r.v_s, 1e-12);
  EXPECT_LT(r.v_w, 1e-12);
}

// Eq. 77's constant-basis remap does not keep the layer at rest: the average at a surface node is
// biased (measured 3.4 % of rho_w g H and 1e-3 m/s of water flow). This is why the semi-implicit
// default is the linear basis.
TEST(SemiImplicit, E1NodeRemapDisturbsTheLayer) {
  const Rest r = run_e1("semi-implicit-single-point", "node-remap", "e1-si-remap");
  EXPECT_GT(r.p_max, 0.01);
  EXPECT_LT(r.p_max, 0.1);
  EXPECT_GT(r.v_w, 1e-4);
}

// E1 with B-splines: the pressure field is exact (the linear fit reproduces the hydrostatic field
// at every node, the extrapolated free-surface nodes included), but point quadrature of the
// effective stress is not exact where a support is cut by the free surface or by the clamped
// knots, so the layer moves a little and settles. Measured over 0.3 s (frames every 0.05 s, implicit
// drag, 2026-12-02): bspline2 p error 0.13 % of rho_w g H, |v_s| 1.9e-4 m/s, |v_w| 1.8e-4
// (single-point) / 1.4e-5 m/s (double-point); bspline3 0.37 %, 1.4e-3 m/s (its 4-node-wide support
// is under-integrated by 2x2 points per cell, as in explicit-single-point: 4.1e-3 m/s). Sampled
// every 0.01 s the single-point bspline2 speed peaks at 2.8e-4 m/s at 0.02 s with either drag form
// and decays to 1e-5 m/s by 0.3 s and 2e-8 m/s by 3 s: hence 5e-4 (the seed's drag read 6.4e-5 at
// the 0.05 s frames only because of where they fall).
TEST(SemiImplicit, E1BsplinesNearlyAtRest) {
  for (const std::string f : {"semi-implicit-single-point", "semi-implicit-double-point"}) {
    const Rest b2 = run_e1(f, "mfvp-linear", "e1-b2-" + f, "bspline2");
    EXPECT_LT(b2.p_max, 0.005) << f;
    EXPECT_LT(b2.v_s, 5e-4) << f;
    EXPECT_LT(b2.v_w, 5e-4) << f;
    const Rest b3 = run_e1(f, "mfvp-linear", "e1-b3-" + f, "bspline3");
    EXPECT_LT(b3.p_max, 0.01) << f;
    EXPECT_LT(b3.v_s, 3e-3) << f;
    EXPECT_LT(b3.v_w, 3e-3) << f;
  }
}
