// Every run reports its own stability indicators (issue 26, item 4): run.json's `stability` (per
// frame and worst) and log.txt. A good run of each kind reports them below their thresholds, the
// values are the library's on the frames the run wrote (the suite and the user see the same
// numbers), what a formulation lacks is omitted with the reason, and a bad run that stays finite
// gets one warning naming the indicator, the place and the time, then a summary at the end.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "solver/diagnostics/stability.hpp"
#include "support/indicators.hpp"
#include "support/run_helpers.hpp"

namespace {

using nlohmann::json;
using swmpm::testing::load_json;
using swmpm::testing::read_text;
namespace dg = swmpm::diagnostics;

/// Occurrences of `what` in `text`.
int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

/// The run's stability record, checked for the shape every run has: one history entry per
/// measured frame for each indicator that exists.
json stability_of(const std::string& run) {
  const json rj = load_json(run + "/run.json");
  EXPECT_TRUE(rj.contains("stability")) << run;
  const json st = rj["stability"];
  const std::size_t frames = st["frames"]["time"].size();
  EXPECT_GE(frames, 2u);
  for (int k = 0; k < dg::kIndicators; ++k) {
    const char* key = dg::kSpecs[k].key;
    EXPECT_EQ(st["thresholds"][key].begin().value().get<double>(), dg::kSpecs[k].threshold) << key;
    if (st["omitted"].contains(key)) {
      EXPECT_FALSE(st["frames"].contains(key)) << key;
      EXPECT_TRUE(st["worst"][key].is_null()) << key;
    } else {
      EXPECT_EQ(st["frames"][key].size(), frames) << key;
    }
  }
  return st;
}

/// Every indicator that exists and was measured is on the good side of its threshold.
void expect_below_thresholds(const json& st, const std::string& what) {
  for (int k = 0; k < dg::kIndicators; ++k) {
    const auto& w = st["worst"][dg::kSpecs[k].key];
    if (w.is_null()) continue;
    EXPECT_FALSE(dg::crosses(static_cast<dg::Indicator>(k), w["value"].get<double>()))
        << what << ": " << dg::kSpecs[k].key << " " << w.dump();
    EXPECT_EQ(w["crossed_frames"], 0) << what << ": " << dg::kSpecs[k].key;
  }
  EXPECT_TRUE(st["warnings"].empty()) << what << ": " << st["warnings"].dump();
}

double last(const json& st, const char* key) { return st["frames"][key].back().get<double>(); }

}  // namespace

// A1 Terzaghi (explicit-single-point) to 0.05 s: every indicator exists and stays below its
// threshold; the checkerboard indices in run.json are the library's on the last frame's VTU with
// radius 1.6 spacings (h / 2 = 0.025 m); log.txt has a line per frame and the summary.
TEST(StabilityIndicators, TerzaghiReportsEveryIndicatorBelowItsThreshold) {
  json s = load_json(SWMPM_SOURCE_DIR "/examples/terzaghi/scene.json");
  s["time"]["end"] = 0.05;
  s["output"]["interval"] = 0.01;
  const std::string run = swmpm::testing::run_scene(s, "stab-terzaghi", 1);
  const json st = stability_of(run);
  EXPECT_EQ(st["frames"]["time"].size(), 6u);
  EXPECT_TRUE(st["omitted"].empty()) << st["omitted"].dump();
  expect_below_thresholds(st, "terzaghi");
  const auto f = swmpm::testing::last_frame(run);
  const double radius = 1.6 * 0.025;
  EXPECT_NEAR(last(st, "pressure_checkerboard"),
              swmpm::testing::checkerboard_indicator(f, f.get("pore_pressure", "frame").values, radius), 1e-12);
  EXPECT_NEAR(last(st, "mean_stress_checkerboard"),
              swmpm::testing::checkerboard_indicator(f, f.get("mean_effective_stress", "frame").values, radius), 1e-12);
  EXPECT_GT(last(st, "pressure_checkerboard"), 0.0);  // the boundary layer under the drained top is not a plane
  EXPECT_NEAR(last(st, "porosity_min"), 0.3, 0.01);
  EXPECT_NEAR(last(st, "J_min"), 1.0, 0.01);
  EXPECT_EQ(last(st, "cavitation_fraction"), 0.0);
  const std::string log = read_text(run + "/log.txt");
  EXPECT_EQ(count(log, "stability at t = "), 6);
  EXPECT_NE(log.find("stability at t = 0.05 s: p checkerboard "), std::string::npos) << log;
  EXPECT_NE(log.find("stability over 6 frames (worst values): pressure_checkerboard "), std::string::npos) << log;
  EXPECT_EQ(log.find("warning: stability"), std::string::npos) << log;
}

// A dry run has no pore pressure and no porosity: those indicators are omitted with the reason.
// The elastic column (gravity on at t = 0, undamped) to 0.1 s: the base's points are at rest.
TEST(StabilityIndicators, DryRunOmitsWhatItDoesNotHave) {
  json s = load_json(SWMPM_SOURCE_DIR "/examples/elastic-column/scene.json");
  s["time"]["end"] = 0.1;
  s["output"]["interval"] = 0.05;
  const std::string run = swmpm::testing::run_scene(s, "stab-dry", 1);
  const json st = stability_of(run);
  for (const char* key : {"pressure_checkerboard", "cavitation_fraction", "porosity_min", "porosity_max"})
    EXPECT_TRUE(st["omitted"].contains(key)) << key;
  EXPECT_EQ(st["omitted"]["pressure_checkerboard"], "no pore or free water in this run");
  EXPECT_FALSE(st["frames"].contains("pressure_checkerboard"));
  expect_below_thresholds(st, "dry column");
  EXPECT_TRUE(st["frames"]["spurious_velocity"][0].is_null());  // nothing has moved at t = 0
  EXPECT_FALSE(st["frames"]["spurious_velocity"].back().is_null());
  EXPECT_EQ(st["worst"]["mean_stress_checkerboard"]["where"]["set"], "solid");
}
