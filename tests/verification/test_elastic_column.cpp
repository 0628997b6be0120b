// Elastic column under self-weight, roller sides, fixed base (1D strain):
//   sigma_yy(y) = -rho g (H - y),  sigma_xx = nu/(1-nu) sigma_yy,  settlement u = rho g H^2 / (2 M),
//   M = E (1 - nu) / ((1 + nu)(1 - 2 nu)).
// Gravity is ramped over 0.5 s (>3 periods of the first mode) and local damping removes the rest
// of the oscillation; the column is checked at 1.0 s against the static solution, in 2D and 3D.
#include <gtest/gtest.h>

#include <cmath>

#include "support/run_helpers.hpp"

namespace {

using nlohmann::json;

constexpr double rho = 1800.0, g = 9.81, H = 1.0, E = 1.0e6, nu = 0.3;

json column_scene(int dim, const std::string& shape) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/elastic-column/scene.json");
  s["grid"]["shape_function"] = shape;
  if (dim == 3) {
    s["dimension"] = 3;
    s["gravity"] = {0.0, -9.81, 0.0};
    s["grid"]["min"] = {0.0, 0.0, 0.0};
    s["grid"]["max"] = {0.1, 1.1, 0.1};
    s["bodies"][0]["geometry"]["min"] = {0.0, 0.0, 0.0};
    s["bodies"][0]["geometry"]["max"] = {0.1, 1.0, 0.1};
    s["boundaries"].push_back({{"on", "z_min"}, {"solid", "roller"}});
    s["boundaries"].push_back({{"on", "z_max"}, {"solid", "roller"}});
    s["output"]["monitors"][0]["at"] = {0.05, 1.0, 0.05};
    s["output"]["monitors"][1]["at"] = {0.05, 0.0, 0.05};
  }
  return s;
}

struct ColumnErrors {
  double settlement_rel;  // |u_top - u| / u
  double stress_yy_rms;   // RMS(sigma_yy - exact) / (rho g H)
  double stress_xx_rms;   // RMS(sigma_xx - exact) / (rho g H)
};

ColumnErrors run_column(int dim, const std::string& shape) {
  const std::string run = swmpm::testing::run_scene(column_scene(dim, shape), "column" + std::to_string(dim) + shape);
  const auto frame = swmpm::testing::last_frame(run);
  const auto& stress = frame.get("stress", "frame");
  const auto& disp = frame.get("displacement", "frame");
  double e_yy = 0.0, e_xx = 0.0, u_top = 0.0;
  const double K0 = nu / (1 - nu), scale = rho * g * H;
  for (std::size_t p = 0; p < frame.size(); ++p) {
    const double y0 = frame.points[p][1] - disp.values[3 * p + 1];
    const double exact = -rho * g * (H - y0);
    e_yy += std::pow((stress.values[6 * p + 1] - exact) / scale, 2);
    e_xx += std::pow((stress.values[6 * p + 0] - K0 * exact) / scale, 2);
    u_top = std::min(u_top, disp.values[3 * p + 1]);
  }
  const double M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu));
  const double n = static_cast<double>(frame.size());
  // u(y) = rho g (H y - y^2 / 2) / M; the top particles sit half a particle spacing below H.
  const double y_top = H - 0.25 * 0.05;
  const double u_exact_top = rho * g * (H * y_top - 0.5 * y_top * y_top) / M;
  return {std::abs(-u_top - u_exact_top) / u_exact_top, std::sqrt(e_yy / n), std::sqrt(e_xx / n)};
}

}  // namespace

// Tolerances: settlement within 2 %, stresses within 2 % RMS of rho g H.
TEST(ElasticColumn, Gimp2D) {
  const auto e = run_column(2, "gimp");
  RecordProperty("settlement_rel_error", std::to_string(e.settlement_rel));
  std::printf("2D gimp: settlement error %.4f %%, sigma_yy RMS %.4f %%, sigma_xx RMS %.4f %%\n",
              100 * e.settlement_rel, 100 * e.stress_yy_rms, 100 * e.stress_xx_rms);
  EXPECT_LT(e.settlement_rel, 0.02);
  EXPECT_LT(e.stress_yy_rms, 0.02);
  EXPECT_LT(e.stress_xx_rms, 0.02);
}

TEST(ElasticColumn, Gimp3D) {
  const auto e = run_column(3, "gimp");
  std::printf("3D gimp: settlement error %.4f %%, sigma_yy RMS %.4f %%, sigma_xx RMS %.4f %%\n",
              100 * e.settlement_rel, 100 * e.stress_yy_rms, 100 * e.stress_xx_rms);
  EXPECT_LT(e.settlement_rel, 0.02);
  EXPECT_LT(e.stress_yy_rms, 0.02);
  EXPECT_LT(e.stress_xx_rms, 0.02);
}

TEST(ElasticColumn, EveryShapeFunction2D) {
  for (const char* shape : {"linear", "bspline2", "bspline3"}) {
    const auto e = run_column(2, shape);
    std::printf("2D %s: settlement error %.4f %%, sigma_yy RMS %.4f %%, sigma_xx RMS %.4f %%\n", shape,
                100 * e.settlement_rel, 100 * e.stress_yy_rms, 100 * e.stress_xx_rms);
    EXPECT_LT(e.settlement_rel, 0.02) << shape;
    EXPECT_LT(e.stress_yy_rms, 0.03) << shape;
  }
}
