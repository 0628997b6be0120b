// Independent finite-element reference for B6, the elastic strip footing of seed 001 App. A
// (this folder's scene.json): tests/support/strip_footing_fe.hpp (Q2/P1-discontinuous mixed
// elements, which do not lock at ν = 0.49) on the half model 10 x 10 m, rollers on both sides,
// fixed base, 20 kPa on 0 <= x <= 3 m of the top; E = 10 MPa, ν = 0.49; static, linear.
//
// Built with the project as build/bench/strip_footing_fe_check, run by hand:
//   strip_footing_fe_check [ELEMENTS_PER_SIDE=80 [POINTS.csv]]
// Prints the settlement at the footing centre (x = 0, y = 10 m) and at the centre of the MPM's
// first particle (0.05, 9.95), the vertical stress and the mean stress on the centreline at a few
// depths, next to the Boussinesq strip-load stress of an elastic half-space (shallow depths only:
// the layer is 10 m deep and 10 m wide), for the README's table. With POINTS.csv (lines "x,y", a
// header line allowed) it prints instead "x,y,u_y,sigma_yy,p" [m, m, m, Pa, Pa] at each point.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <string>

#include "support/strip_footing_fe.hpp"

int main(int argc, char** argv) {
  const int ne = argc > 1 ? std::atoi(argv[1]) : 80;
  constexpr double W = 10.0, H = 10.0, B = 3.0, q = 2.0e4, E = 1.0e7, nu = 0.49;
  const swmpm::testing::StripFootingFE fe(W, H, B, q, E, nu, ne);
  if (argc > 2) {
    std::ifstream in(argv[2]);
    std::string line;
    std::printf("x,y,u_y,sigma_yy,p\n");
    while (std::getline(in, line)) {
      double x, y;
      if (std::sscanf(line.c_str(), "%lf,%lf", &x, &y) != 2) continue;
      const auto s = fe.stress(x, y);
      std::printf("%.6g,%.6g,%.9e,%.9e,%.9e\n", x, y, fe.displacement(x, y)[1], s.yy, s.mean());
    }
    return 0;
  }
  std::printf("strip footing FE, %d x %d Q2/P1 elements (h = %.4f m)\n", ne, ne, W / ne);
  std::printf("u_y(0, 10)        = %.6e m\n", fe.displacement(0.0, H)[1]);
  std::printf("u_y(0.05, 9.95)   = %.6e m\n", fe.displacement(0.05, H - 0.05)[1]);
  std::printf("u_y(3, 10)        = %.6e m  (footing edge)\n", fe.displacement(B, H)[1]);
  std::printf("%8s %14s %14s %14s\n", "depth", "sigma_yy/q", "p/q", "Boussinesq");
  for (double z : {0.25, 0.5, 1.0, 2.0, 3.0, 5.0, 7.5}) {
    const auto s = fe.stress(0.05, H - z);
    // Centreline of a strip of half-width b on a half-space: σ_z = (q/π)(α + sin α), α = 2 atan(b/z).
    const double alpha = 2.0 * std::atan(B / z);  // B: the half-width (the footing is 2B = 6 m wide)
    const double boussinesq = (alpha + std::sin(alpha)) / std::numbers::pi;
    std::printf("%8.3f %14.5f %14.5f %14.5f\n", z, -s.yy / q, s.mean() / q, boussinesq);
  }
  return 0;
}
