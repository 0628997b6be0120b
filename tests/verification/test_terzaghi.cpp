// A1 (seed 000 §4.1.1): Terzaghi's 1D consolidation with explicit-single-point.
// Column 0.1 x 1.0 m, cells 0.05 m, 2x2 particles per cell; E = 10 MPa, nu = 0, rho_s = 2650,
// rho_w = 1000, n = 0.3, K_f = 2.2 GPa, k = 1e-3 m/s; sides roller + impermeable, base fixed +
// impermeable, top free and drained; initial p0 = 10 kPa, sigma' = 0, a 10 kPa traction on top,
// no gravity. Analytic (drained top, impermeable base, z = depth below the top):
//   p / p0 = sum_m (2/M) sin(M z / H) exp(-M^2 Tv),  M = (2m + 1) pi / 2,  Tv = c_v t / H^2,
//   c_v = k / (gamma_w (1/E_oed + n / K_f)).
#include <gtest/gtest.h>

#include <cmath>

#include "scene/scene.hpp"
#include "support/run_helpers.hpp"

namespace {

using nlohmann::json;

constexpr double H = 1.0, p0 = 1.0e4, E = 1.0e7, n0 = 0.3, rho_s = 2650.0, rho_w = 1000.0, K_f = 2.2e9,
                 k = 1.0e-3, g = 9.81;

double terzaghi(double z, double Tv) {
  double sum = 0.0;
  for (int m = 0; m < 200; ++m) {
    const double M = (2 * m + 1) * M_PI / 2;
    sum += 2.0 / M * std::sin(M * z / H) * std::exp(-M * M * Tv);
  }
  return sum;
}

json scene_a1(const std::string& stabilisation_pressure, bool smoothing, double end) {
  json s = json::parse(R"json({
    "name": "terzaghi", "dimension": 2, "formulation": "explicit-single-point",
    "grid": { "cell_size": 0.05, "min": [0.0, 0.0], "max": [0.1, 1.1], "shape_function": "gimp" },
    "materials": [
      { "name": "sand", "model": "linear-elastic", "grain_density": 2650.0, "porosity": 0.3,
        "youngs_modulus": 1.0e7, "poisson_ratio": 0.0, "hydraulic_conductivity": 1.0e-3 },
      { "name": "water", "model": "fluid", "density": 1000.0, "bulk_modulus": 2.2e9 } ],
    "bodies": [ { "name": "column", "geometry": { "type": "box", "min": [0.0, 0.0], "max": [0.1, 1.0] },
                  "solid": "sand", "fluid": "water", "particles_per_cell": 2, "initial": { "pore_pressure": 1.0e4 } } ],
    "boundaries": [ { "on": "x_min", "solid": "roller", "fluid": "impermeable" },
                    { "on": "x_max", "solid": "roller", "fluid": "impermeable" },
                    { "on": "y_min", "solid": "fixed", "fluid": "impermeable" } ],
    "loads": [ { "type": "traction", "body": "column", "face": "y_max", "value": [0.0, -1.0e4] } ],
    "time": { "end": 0.5, "dt": 1.0e-5 },
    "output": { "interval": 0.05, "monitors": [
      { "name": "base", "at": [0.05, 0.0], "phase": "fluid", "quantities": ["pore_pressure"] },
      { "name": "top", "at": [0.05, 1.0], "phase": "solid", "quantities": ["displacement_y"] } ] }
  })json");
  s["solver"] = {{"stabilisation", {{"pressure", stabilisation_pressure}, {"strain_smoothing", smoothing}}}};
  s["time"]["end"] = end;
  return s;
}

}  // namespace

TEST(Terzaghi, A1PorePressureProfilesMatchTheSeries) {
  const std::string run = swmpm::testing::run_scene(scene_a1("mfvp-constant", true, 0.5), "terzaghi");
  const double c_v = k / (rho_w * g * (1.0 / E + n0 / K_f));
  const auto entries = swmpm::scene::read_pvd(run + "/output/results.pvd");
  int checked = 0;
  for (const auto& e : entries) {
    if (e.time < 0.04) continue;
    const auto f = swmpm::scene::read_vtu(run + "/output/" + e.file);
    const auto& pp = f.get("pore_pressure", e.file).values;
    const auto& d = f.get("displacement", e.file).values;
    const double Tv = c_v * e.time / (H * H);
    double err2 = 0.0;
    for (std::size_t p = 0; p < f.size(); ++p) {
      const double z = H - (f.points[p][1] - d[3 * p + 1]);  // depth below the top, reference position
      err2 += std::pow(pp[p] / p0 - terzaghi(z, Tv), 2);
    }
    const double rms = std::sqrt(err2 / static_cast<double>(f.size()));
    std::printf("Terzaghi A1: t = %.3f s, Tv = %.3f, RMS error of p/p0 = %.4f\n", e.time, Tv, rms);
    EXPECT_LT(rms, 0.03) << "Tv = " << Tv;
    ++checked;
  }
  EXPECT_GE(checked, 5);
}
