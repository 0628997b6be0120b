// Independent finite-element reference for B6 (seed 001 App. A, examples/strip-footing-fbar): the
// static, linear-elastic, plane-strain half model W x H with rollers on x = 0 and x = W, a fixed
// base y = 0, and a uniform pressure q on 0 <= x <= B of the top y = H.
//
// Elements: Q2/P1-discontinuous mixed quadrilaterals (the 9-node biquadratic "Q9/3" element;
// Brezzi & Fortin; Hughes, "The Finite Element Method" §4.5): displacements biquadratic, the
// pressure linear and discontinuous per element (1, ξ, η), condensed per element. With
// p = K ε̄_v, ε̄_v the L2 projection of div u onto the element's pressure space, the element matrix
// is K_dev + K Gᵀ M⁻¹ G,  K_dev = ∫ Bᵀ D_dev B (3x3 Gauss),  G = ∫ q (div N)ᵀ,  M = ∫ q qᵀ.
// The element satisfies the inf-sup condition, so it does not lock as ν → 1/2 (ν = 0.49 here).
// Stresses: σ = 2G dev ε + K ε̄_v 1 (plane strain, ε_zz = 0), so the mean stress is K ε̄_v.
//
// Only Eigen; used by tests/verification/test_strip_footing_fbar.cpp and
// examples/strip-footing-fbar/fe_check.cpp (built as build/bench/strip_footing_fe_check).
#pragma once

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace swmpm::testing {

class StripFootingFE {
 public:
  struct Stress {
    double xx, yy, zz, xy;  // Pa, tension positive
    double mean() const { return -(xx + yy + zz) / 3.0; }  // p, compression positive
  };

  /// ne x ne elements (B / (W / ne) must be whole). E [Pa], nu [-], q [Pa] pushing down.
  StripFootingFE(double W, double H, double B, double q, double E, double nu, int ne)
      : ne_(ne), hx_(W / ne), hy_(H / ne) {
    const double G = E / (2.0 * (1.0 + nu)), K = E / (3.0 * (1.0 - 2.0 * nu));
    G_ = G, K_ = K;
    const double loaded = B / hx_;
    if (std::abs(loaded - std::round(loaded)) > 1e-9) throw std::invalid_argument("B must fall on an element edge");
    const int nn = 2 * ne + 1, ndof = 2 * nn * nn;
    std::vector<Eigen::Triplet<double>> trip;
    pressure_.assign(static_cast<std::size_t>(ne) * ne, Eigen::Vector3d::Zero());
    const Eigen::Matrix<double, 18, 18> Ke = element_matrix(proj_);
    for (int ey = 0; ey < ne; ++ey)
      for (int ex = 0; ex < ne; ++ex) {
        const auto d = dofs(ex, ey);
        for (int a = 0; a < 18; ++a)
          for (int b = 0; b < 18; ++b) trip.emplace_back(d[a], d[b], Ke(a, b));
      }
    Eigen::SparseMatrix<double> A(ndof, ndof);
    A.setFromTriplets(trip.begin(), trip.end());
    Eigen::VectorXd f = Eigen::VectorXd::Zero(ndof);
    // Consistent loads of a quadratic edge under a uniform traction: l/6, 4l/6, l/6.
    for (int ex = 0; ex < static_cast<int>(std::round(loaded)); ++ex) {
      const double w[3] = {hx_ / 6.0, 4.0 * hx_ / 6.0, hx_ / 6.0};
      for (int k = 0; k < 3; ++k) f[2 * node(2 * ex + k, 2 * ne) + 1] -= q * w[k];
    }
    // Dirichlet: u_x = 0 on x = 0 and x = W, u = 0 on y = 0 (row/column elimination with a unit diagonal).
    std::vector<char> fixed(ndof, 0);
    for (int j = 0; j < nn; ++j) fixed[2 * node(0, j)] = fixed[2 * node(nn - 1, j)] = 1;
    for (int i = 0; i < nn; ++i) fixed[2 * node(i, 0)] = fixed[2 * node(i, 0) + 1] = 1;
    for (int k = 0; k < A.outerSize(); ++k)
      for (Eigen::SparseMatrix<double>::InnerIterator it(A, k); it; ++it)
        if (fixed[it.row()] || fixed[it.col()]) it.valueRef() = it.row() == it.col() ? 1.0 : 0.0;
    for (int k = 0; k < ndof; ++k)
      if (fixed[k]) f[k] = 0.0;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
    if (solver.info() != Eigen::Success) throw std::runtime_error("strip footing FE: factorisation failed");
    u_ = solver.solve(f);
    for (int ey = 0; ey < ne; ++ey)
      for (int ex = 0; ex < ne; ++ex) {
        const auto d = dofs(ex, ey);
        Eigen::Matrix<double, 18, 1> ue;
        for (int a = 0; a < 18; ++a) ue[a] = u_[d[a]];
        pressure_[ey * ne + ex] = proj_ * ue;  // coefficients of ε̄_v in (1, ξ, η)
      }
  }

  /// Displacement (u_x, u_y) [m] at (x, y).
  Eigen::Vector2d displacement(double x, double y) const {
    int ex, ey;
    double xi, eta;
    locate(x, y, ex, ey, xi, eta);
    const auto N = shape(xi, eta);
    const auto d = dofs(ex, ey);
    Eigen::Vector2d out = Eigen::Vector2d::Zero();
    for (int a = 0; a < 9; ++a) out += N[a] * Eigen::Vector2d(u_[d[2 * a]], u_[d[2 * a + 1]]);
    return out;
  }

  /// Stress at (x, y): σ = 2G dev ε + K ε̄_v 1, ε_zz = 0.
  Stress stress(double x, double y) const {
    int ex, ey;
    double xi, eta;
    locate(x, y, ex, ey, xi, eta);
    const auto d = dofs(ex, ey);
    const Eigen::Matrix<double, 3, 18> Bm = strain_matrix(xi, eta);
    Eigen::Matrix<double, 18, 1> ue;
    for (int a = 0; a < 18; ++a) ue[a] = u_[d[a]];
    const Eigen::Vector3d e = Bm * ue;  // εxx, εyy, γxy
    const double ev = e[0] + e[1];
    const double ev_bar = pressure_[ey * ne_ + ex].dot(Eigen::Vector3d(1.0, xi, eta));
    const double m = K_ * ev_bar;
    return {2.0 * G_ * (e[0] - ev / 3.0) + m, 2.0 * G_ * (e[1] - ev / 3.0) + m, 2.0 * G_ * (-ev / 3.0) + m,
            G_ * e[2]};
  }

 private:
  int node(int i, int j) const { return j * (2 * ne_ + 1) + i; }
  /// Dofs of element (ex, ey): its 9 nodes i + 3 j (local i, j = 0, 1, 2 along x, y), x then y.
  std::array<int, 18> dofs(int ex, int ey) const {
    std::array<int, 18> d{};
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        const int a = i + 3 * j, n = node(2 * ex + i, 2 * ey + j);
        d[2 * a] = 2 * n;
        d[2 * a + 1] = 2 * n + 1;
      }
    return d;
  }
  void locate(double x, double y, int& ex, int& ey, double& xi, double& eta) const {
    ex = std::clamp(static_cast<int>(std::floor(x / hx_)), 0, ne_ - 1);
    ey = std::clamp(static_cast<int>(std::floor(y / hy_)), 0, ne_ - 1);
    xi = 2.0 * (x - (ex + 0.5) * hx_) / hx_;
    eta = 2.0 * (y - (ey + 0.5) * hy_) / hy_;
  }
  /// 1D quadratic Lagrange on nodes −1, 0, 1 and its derivative.
  static void lagrange(double s, double l[3], double dl[3]) {
    l[0] = 0.5 * s * (s - 1.0), l[1] = 1.0 - s * s, l[2] = 0.5 * s * (s + 1.0);
    dl[0] = s - 0.5, dl[1] = -2.0 * s, dl[2] = s + 0.5;
  }
  static std::array<double, 9> shape(double xi, double eta) {
    double lx[3], dlx[3], ly[3], dly[3];
    lagrange(xi, lx, dlx);
    lagrange(eta, ly, dly);
    std::array<double, 9> N{};
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) N[i + 3 * j] = lx[i] * ly[j];
    return N;
  }
  Eigen::Matrix<double, 3, 18> strain_matrix(double xi, double eta) const {
    double lx[3], dlx[3], ly[3], dly[3];
    lagrange(xi, lx, dlx);
    lagrange(eta, ly, dly);
    Eigen::Matrix<double, 3, 18> Bm = Eigen::Matrix<double, 3, 18>::Zero();
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        const int a = i + 3 * j;
        const double dx = dlx[i] * ly[j] * 2.0 / hx_, dy = lx[i] * dly[j] * 2.0 / hy_;
        Bm(0, 2 * a) = dx;
        Bm(1, 2 * a + 1) = dy;
        Bm(2, 2 * a) = dy;
        Bm(2, 2 * a + 1) = dx;
      }
    return Bm;
  }
  /// The condensed element matrix (the same for every element of the uniform mesh) and the
  /// projection P = M⁻¹ G (coefficients of ε̄_v from the element's displacements).
  Eigen::Matrix<double, 18, 18> element_matrix(Eigen::Matrix<double, 3, 18>& P) const {
    const double g[3] = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)}, wg[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
    Eigen::Matrix3d Ddev;
    Ddev << 4.0 / 3.0 * G_, -2.0 / 3.0 * G_, 0.0, -2.0 / 3.0 * G_, 4.0 / 3.0 * G_, 0.0, 0.0, 0.0, G_;
    const double detJ = 0.25 * hx_ * hy_;
    Eigen::Matrix<double, 18, 18> Kd = Eigen::Matrix<double, 18, 18>::Zero();
    Eigen::Matrix<double, 3, 18> Gm = Eigen::Matrix<double, 3, 18>::Zero();
    Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const double w = wg[a] * wg[b] * detJ;
        const Eigen::Matrix<double, 3, 18> Bm = strain_matrix(g[a], g[b]);
        Kd += w * Bm.transpose() * Ddev * Bm;
        const Eigen::Vector3d qv(1.0, g[a], g[b]);
        const Eigen::Matrix<double, 1, 18> div = Bm.row(0) + Bm.row(1);
        Gm += w * qv * div;
        M += w * qv * qv.transpose();
      }
    P = M.inverse() * Gm;
    return Kd + K_ * Gm.transpose() * P;
  }

  int ne_;
  double hx_, hy_, G_ = 0.0, K_ = 0.0;
  Eigen::VectorXd u_;
  std::vector<Eigen::Vector3d> pressure_;                 // per element: ε̄_v coefficients
  Eigen::Matrix<double, 3, 18> proj_;                     // M⁻¹ G (the same for every element)
};

}  // namespace swmpm::testing
