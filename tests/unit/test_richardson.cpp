// Richardson extrapolation of `swmpm study` (study/richardson.hpp) on sequences with a known
// limit, and the rules that flag runs outside the asymptotic range; the page writer's base64.
#include <gtest/gtest.h>

#include <cmath>

#include "postprocess/page.hpp"
#include "study/richardson.hpp"

using swmpm::study::extrapolate;

namespace {

/// q(h) = limit + C h^p at h = 1, 1/r, 1/r^2, ...
std::vector<std::vector<double>> power_law(double limit, double C, double p, double r, int levels) {
  std::vector<std::vector<double>> q;
  for (int k = 0; k < levels; ++k) q.push_back({limit + C * std::pow(r, -p * k)});
  return q;
}

}  // namespace

TEST(Richardson, RecoversOrderLimitAndErrorsOfAPowerLaw) {
  for (double p : {1.0, 2.0, 3.0})
    for (double r : {2.0, std::sqrt(2.0), 1.5}) {
      const auto e = extrapolate(power_law(3.0, -0.4, p, r, 4), r, 3.0);
      EXPECT_TRUE(e.asymptotic) << e.why;
      EXPECT_NEAR(e.order, p, 1e-9);
      ASSERT_EQ(e.orders.size(), 2u);
      EXPECT_NEAR(e.orders[0], p, 1e-9);
      EXPECT_NEAR(e.extrapolated[0], 3.0, 1e-12);
      for (int k = 0; k < 4; ++k) EXPECT_NEAR(e.error[static_cast<std::size_t>(k)], 0.4 * std::pow(r, -p * k), 1e-12);
    }
}

TEST(Richardson, HistoriesUseTheRmsOfTheChanges) {
  // q_k(t) = sin t + C h_k^2 cos t: order 2, the limit sin t, the error RMS(C h^2 cos t).
  std::vector<std::vector<double>> q(3);
  const std::vector<double> h{0.1, 0.05, 0.025};
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 20; ++i) q[static_cast<std::size_t>(k)].push_back(std::sin(0.3 * i) + 5.0 * h[static_cast<std::size_t>(k)] * h[static_cast<std::size_t>(k)] * std::cos(0.3 * i));
  const auto e = extrapolate(q, 2.0, 1.0);
  EXPECT_TRUE(e.asymptotic);
  EXPECT_NEAR(e.order, 2.0, 1e-9);
  for (int i = 0; i < 20; ++i) EXPECT_NEAR(e.extrapolated[static_cast<std::size_t>(i)], std::sin(0.3 * i), 1e-12);
  std::vector<double> err;
  for (int i = 0; i < 20; ++i) err.push_back(5.0 * 0.025 * 0.025 * std::cos(0.3 * i));
  EXPECT_NEAR(e.error[2], swmpm::study::rms(err), 1e-12);
}

TEST(Richardson, FlagsRunsOutsideTheAsymptoticRange) {
  // Oscillating: the changes flip sign.
  auto e = extrapolate({{1.0}, {1.2}, {1.1}}, 2.0, 1.0);
  EXPECT_FALSE(e.asymptotic);
  EXPECT_NE(e.why.find("oscillating"), std::string::npos);
  EXPECT_DOUBLE_EQ(e.extrapolated[0], 1.1);                 // not extrapolated
  EXPECT_NEAR(e.error[2], 0.1 / (2.0 - 1.0), 1e-12);         // first order from the last change
  EXPECT_NEAR(e.error[0], 0.1 + 0.1, 1e-12);                 // |q - q_c| + e_c
  // Not converging: the last change is the larger.
  e = extrapolate({{1.0}, {1.1}, {1.3}}, 2.0, 1.0);
  EXPECT_FALSE(e.asymptotic);
  EXPECT_NE(e.why.find("not converging"), std::string::npos);
  // Orders out of [0.5, 4].
  e = extrapolate(power_law(1.0, 1.0, 0.3, 2.0, 3), 2.0, 1.0);
  EXPECT_FALSE(e.asymptotic);
  EXPECT_NE(e.why.find("below 0.5"), std::string::npos);
  e = extrapolate(power_law(1.0, 1.0, 5.0, 2.0, 3), 2.0, 1.0);
  EXPECT_FALSE(e.asymptotic);
  EXPECT_NE(e.why.find("above 4"), std::string::npos);
  // Round-off: converged, the error the last change.
  e = extrapolate({{1.0}, {1.0 + 1e-15}, {1.0}}, 2.0, 1.0);
  EXPECT_TRUE(e.asymptotic);
  EXPECT_TRUE(e.converged);
  EXPECT_LT(e.error[2], 2e-15);  // the last change, 1e-15 to the double's resolution
}

TEST(Richardson, CellSizeForATolerance) {
  // e = 0.08 at h = 0.1, order 2: 0.02 needs h = 0.05.
  EXPECT_NEAR(swmpm::study::cell_size_for(0.1, 0.08, 0.02, 2.0), 0.05, 1e-12);
  EXPECT_NEAR(swmpm::study::cell_size_for(0.1, 0.08, 0.02, 1.0), 0.025, 1e-12);
}

TEST(Page, Base64OfRfc4648Vectors) {
  EXPECT_EQ(swmpm::post::base64(""), "");
  EXPECT_EQ(swmpm::post::base64("f"), "Zg==");
  EXPECT_EQ(swmpm::post::base64("fo"), "Zm8=");
  EXPECT_EQ(swmpm::post::base64("foo"), "Zm9v");
  EXPECT_EQ(swmpm::post::base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(swmpm::post::base64(std::string("\xff\x00\x80", 3)), "/wCA");
}

TEST(Page, MarkdownAndHtmlFromTheSameBlocks) {
  swmpm::post::Page p;
  p.title = "T <1>";
  p.add_heading("Runs");
  p.add_table({"a", "b|c"}, {{"`x`", "**y**"}});
  const std::string md = p.markdown(), html = p.html(".");
  EXPECT_NE(md.find("| a | b\\|c |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `x` | **y** |"), std::string::npos) << md;
  EXPECT_NE(html.find("<title>T &lt;1&gt;</title>"), std::string::npos);
  EXPECT_NE(html.find("<td><code>x</code></td><td><strong>y</strong></td>"), std::string::npos) << html;
}
