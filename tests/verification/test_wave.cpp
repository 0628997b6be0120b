// A 1D elastic bar (plane strain, nu = 0, roller sides, fixed base, free top) vibrating in its
// first mode v(y) = v0 sin(pi y / 2L): the period is T = 4 L / c with c = sqrt(M / rho).
//  - WaveSpeed: the measured period gives c within 1 %.
//  - FlipVsPic: over 5 periods pure FLIP keeps the total energy (kinetic + strain) within 2 %,
//    pure PIC dissipates a large part of it. Both assertions can fail.
#include <gtest/gtest.h>

#include <cmath>

#include "support/run_helpers.hpp"

namespace {

using nlohmann::json;

constexpr double L = 1.0, E = 1.0e7, rho = 1000.0;

/// The bar [0, 2h] x [0, L] on cells of size h (2 across), FLIP fraction `flip`, run to `end`.
json bar_scene(double flip, double h, double end) {
  json s = json::parse(R"json({
    "name": "bar", "dimension": 2, "formulation": "dry",
    "grid": { "cell_size": 0.05, "min": [0.0, 0.0], "max": [0.1, 1.2], "shape_function": "gimp" },
    "materials": [ { "name": "m", "model": "linear-elastic", "density": 1000.0,
                     "youngs_modulus": 1.0e7, "poisson_ratio": 0.0 } ],
    "bodies": [ { "name": "bar", "geometry": { "type": "box", "min": [0.0, 0.0], "max": [0.1, 1.0] },
                  "solid": "m", "particles_per_cell": 2,
                  "initial": { "velocity": ["0", "0.01*sin(pi*y/2)"] } } ],
    "boundaries": [ { "on": "x_min", "solid": "roller" }, { "on": "x_max", "solid": "roller" },
                    { "on": "y_min", "solid": "fixed" } ],
    "time": { "end": 0.2, "dt": "auto", "cfl": 0.5 },
    "output": { "interval": 0.1, "monitors": [
      { "name": "top", "at": [0.05, 1.0], "phase": "solid", "quantities": ["velocity_y"] },
      { "name": "energy", "quantities": ["kinetic_energy", "strain_energy", "total_energy"] } ] }
  })json");
  s["solver"] = {{"flip", flip}};
  s["time"]["end"] = end;
  s["grid"]["cell_size"] = h;
  s["grid"]["max"] = {2 * h, 1.2};
  s["bodies"][0]["geometry"]["max"] = {2 * h, L};
  s["output"]["monitors"][0]["at"] = {h, L};
  return s;
}

/// Period from the downward zero crossings of the top velocity (linear interpolation).
double measured_period(const swmpm::post::Table& t) {
  const auto& time = t.column("time");
  const auto& v = t.column("top.velocity_y");
  std::vector<double> crossings;
  for (std::size_t k = 1; k < v.size(); ++k)
    if (v[k - 1] > 0.0 && v[k] <= 0.0) crossings.push_back(time[k - 1] + (time[k] - time[k - 1]) * v[k - 1] / (v[k - 1] - v[k]));
  EXPECT_GE(crossings.size(), 3u);
  return (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
}

}  // namespace

TEST(ElasticBar, WaveSpeed) {
  const std::string run = swmpm::testing::run_scene(bar_scene(1.0, 0.025, 0.2), "wave");
  const auto t = swmpm::post::read_csv(run + "/monitors.csv");
  const double T = measured_period(t);
  const double c_exact = std::sqrt(E / rho);
  const double c_bar = 4.0 * L / T;
  std::printf("period %.6f s, c = %.4f m/s (exact %.4f), error %.3f %%\n", T, c_bar, c_exact,
              100 * std::abs(c_bar - c_exact) / c_exact);
  EXPECT_NEAR(c_bar / c_exact, 1.0, 0.01);
}

TEST(ElasticBar, FlipConservesEnergyPicDissipates) {
  auto energy_ratio = [](double flip, const std::string& name) {
    const std::string run = swmpm::testing::run_scene(bar_scene(flip, 0.05, 0.2), name);
    const auto t = swmpm::post::read_csv(run + "/monitors.csv");
    const auto& e = t.column("energy.total_energy");
    return e.back() / e.front();
  };
  const double flip = energy_ratio(1.0, "flip"), pic = energy_ratio(0.0, "pic");
  std::printf("energy after 5 periods: FLIP %.4f, PIC %.4f of the initial\n", flip, pic);
  EXPECT_NEAR(flip, 1.0, 0.02);
  EXPECT_LT(pic, 0.8);
}
