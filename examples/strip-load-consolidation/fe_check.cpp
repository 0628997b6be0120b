// Independent finite-element check for the strip-load example (A3): plane-strain bilinear (Q1)
// elements with selective reduced integration (deviatoric part 2x2 Gauss points, volumetric part
// one point: no locking in the undrained, nearly incompressible limit), on the same half model:
// an L x L layer, rollers on x = 0, x = L and y = 0, a strip load q on 0 <= x <= B of the top.
//
//   static drained     skeleton alone: E = 10 MPa, nu = 0.3
//   static undrained   no flow: bulk modulus K_u = K' + K_f / n (incompressible grains), same G
//   dynamic undrained  no flow, mixture density rho_sat, load applied at t = 0 and held;
//                      Newmark average acceleration (no numerical damping), lumped mass
//
// Built with the project as build/bench/strip_load_fe_check (Eigen only), run by hand:
//   strip_load_fe_check L B CELLS [dt end [reference.csv]]      e.g. strip_load_fe_check 10 3 80 5e-5 0.1
// Prints the vertical displacement at the top-left corner (x = 0, y = L) and at the initial
// position of the MPM corner monitor's particle, (L/80, L - L/80): the centre of the first
// particle of a 0.5 m (L = 10) or 0.05 m (L = 1) grid with 2x2 particles per cell. With a file
// name, also writes the dynamic history at that point every 1 ms as `time,corner.displacement_y`
// [s, m] (a reference curve for `swmpm postprocess RUN plot --reference` / `compare`).
#include <Eigen/Sparse>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace {

constexpr double E = 1.0e7, nu = 0.3, K_f = 2.2e9, n0 = 0.3, rho_s = 2700.0, rho_f = 1000.0, q = 2.0e4;

struct Model {
  double L, B;
  int ne;  // elements per side
  double h() const { return L / ne; }
  int node(int i, int j) const { return j * (ne + 1) + i; }
};

using Triplets = std::vector<Eigen::Triplet<double>>;

/// Stiffness of the whole mesh (all 2 (ne+1)^2 dofs) for bulk modulus K and shear modulus G.
Eigen::SparseMatrix<double> stiffness(const Model& m, double K, double G) {
  const double h = m.h();
  // Q1 on a square element of side h: dN/dx at (xi, eta) in [-1, 1]^2.
  auto grads = [h](double xi, double eta, double dx[4], double dy[4]) {
    const double sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
    for (int a = 0; a < 4; ++a) {
      dx[a] = 0.25 * sx[a] * (1 + sy[a] * eta) * 2.0 / h;
      dy[a] = 0.25 * sy[a] * (1 + sx[a] * xi) * 2.0 / h;
    }
  };
  // D = K m m^T + D_dev, D_dev = G [[4/3, -2/3, 0], [-2/3, 4/3, 0], [0, 0, 1]] (plane strain).
  Eigen::Matrix3d Ddev;
  Ddev << 4.0 / 3 * G, -2.0 / 3 * G, 0, -2.0 / 3 * G, 4.0 / 3 * G, 0, 0, 0, G;
  Eigen::Matrix3d Dvol = Eigen::Matrix3d::Zero();
  Dvol.topLeftCorner<2, 2>().setConstant(K);
  auto Bmat = [&](double xi, double eta) {
    double dx[4], dy[4];
    grads(xi, eta, dx, dy);
    Eigen::Matrix<double, 3, 8> Bm = Eigen::Matrix<double, 3, 8>::Zero();
    for (int a = 0; a < 4; ++a) {
      Bm(0, 2 * a) = dx[a];
      Bm(1, 2 * a + 1) = dy[a];
      Bm(2, 2 * a) = dy[a];
      Bm(2, 2 * a + 1) = dx[a];
    }
    return Bm;
  };
  Eigen::Matrix<double, 8, 8> ke = Eigen::Matrix<double, 8, 8>::Zero();
  const double gp = 1.0 / std::sqrt(3.0), detJ = h * h / 4.0;
  for (double xi : {-gp, gp})
    for (double eta : {-gp, gp}) {
      const auto Bm = Bmat(xi, eta);
      ke += Bm.transpose() * Ddev * Bm * detJ;
    }
  const auto B0 = Bmat(0.0, 0.0);
  ke += B0.transpose() * Dvol * B0 * (4.0 * detJ);
  Triplets t;
  for (int j = 0; j < m.ne; ++j)
    for (int i = 0; i < m.ne; ++i) {
      const int nodes[4] = {m.node(i, j), m.node(i + 1, j), m.node(i + 1, j + 1), m.node(i, j + 1)};
      for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b) t.emplace_back(2 * nodes[a / 2] + a % 2, 2 * nodes[b / 2] + b % 2, ke(a, b));
    }
  const int ndof = 2 * (m.ne + 1) * (m.ne + 1);
  Eigen::SparseMatrix<double> Kg(ndof, ndof);
  Kg.setFromTriplets(t.begin(), t.end());
  return Kg;
}

/// Consistent nodal forces of q on 0 <= x <= B of the top (B on a node or inside an element).
Eigen::VectorXd load(const Model& m) {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(2 * (m.ne + 1) * (m.ne + 1));
  const double h = m.h();
  for (int i = 0; i < m.ne; ++i) {
    const double x0 = i * h, x1 = std::min((i + 1) * h, m.B);
    if (x1 <= x0) break;
    // integral of the two hats over [x0, x1] (element [i h, (i+1) h])
    auto hatL = [&](double x) { return ((i + 1) * h - x) / h; };
    auto intL = [&](double a, double b) { return 0.5 * (hatL(a) + hatL(b)) * (b - a); };
    const double left = intL(x0, x1), right = (x1 - x0) - left;
    f[2 * m.node(i, m.ne) + 1] -= q * left;
    f[2 * m.node(i + 1, m.ne) + 1] -= q * right;
  }
  return f;
}

/// Free dofs: u_x = 0 on x = 0 and x = L, u_y = 0 on y = 0.
std::vector<int> free_map(const Model& m, int& nfree) {
  std::vector<int> map(2 * (m.ne + 1) * (m.ne + 1), -1);
  nfree = 0;
  for (int j = 0; j <= m.ne; ++j)
    for (int i = 0; i <= m.ne; ++i) {
      const int nd = m.node(i, j);
      if (i != 0 && i != m.ne) map[2 * nd] = nfree++;
      if (j != 0) map[2 * nd + 1] = nfree++;
    }
  return map;
}

Eigen::SparseMatrix<double> reduce(const Eigen::SparseMatrix<double>& A, const std::vector<int>& map, int nfree) {
  Triplets t;
  for (int k = 0; k < A.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, k); it; ++it)
      if (map[it.row()] >= 0 && map[it.col()] >= 0) t.emplace_back(map[it.row()], map[it.col()], it.value());
  Eigen::SparseMatrix<double> R(nfree, nfree);
  R.setFromTriplets(t.begin(), t.end());
  return R;
}

/// u_y at (x, y) by bilinear interpolation of the full nodal vector.
double uy_at(const Model& m, const Eigen::VectorXd& u, double x, double y) {
  const double h = m.h();
  const int i = std::min(static_cast<int>(x / h), m.ne - 1), j = std::min(static_cast<int>(y / h), m.ne - 1);
  const double s = x / h - i, r = y / h - j;
  return (1 - s) * (1 - r) * u[2 * m.node(i, j) + 1] + s * (1 - r) * u[2 * m.node(i + 1, j) + 1] +
         s * r * u[2 * m.node(i + 1, j + 1) + 1] + (1 - s) * r * u[2 * m.node(i, j + 1) + 1];
}

Eigen::VectorXd expand(const Eigen::VectorXd& r, const std::vector<int>& map) {
  Eigen::VectorXd u = Eigen::VectorXd::Zero(static_cast<long>(map.size()));
  for (std::size_t d = 0; d < map.size(); ++d)
    if (map[d] >= 0) u[static_cast<long>(d)] = r[map[d]];
  return u;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: fe_check L B CELLS [dt end]\n");
    return 2;
  }
  const Model m{std::atof(argv[1]), std::atof(argv[2]), std::atoi(argv[3])};
  const double G = E / (2 * (1 + nu)), K = E / (3 * (1 - 2 * nu)), K_u = K + K_f / n0;
  const double rho_sat = (1 - n0) * rho_s + n0 * rho_f;
  const double xm = m.L / 80.0, ym = m.L - m.L / 80.0;  // first particle (0.125, 9.875) at L = 10
  int nfree = 0;
  const auto map = free_map(m, nfree);
  const Eigen::VectorXd f_full = load(m);
  Eigen::VectorXd f(nfree);
  for (std::size_t d = 0; d < map.size(); ++d)
    if (map[d] >= 0) f[map[d]] = f_full[static_cast<long>(d)];

  for (const bool undrained : {false, true}) {
    const auto Kr = reduce(stiffness(m, undrained ? K_u : K, G), map, nfree);
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(Kr);
    const Eigen::VectorXd u = expand(solver.solve(f), map);
    std::printf("static %-9s  L = %g, B = %g, %d x %d cells: u_y corner (0, %g) = %.4f mm, at (%g, %g) = %.4f mm\n",
                undrained ? "undrained" : "drained", m.L, m.B, m.ne, m.ne, m.L, 1e3 * uy_at(m, u, 0, m.L), xm, ym,
                1e3 * uy_at(m, u, xm, ym));
  }
  if (argc < 6) return 0;

  // Dynamic, undrained: M a + K u = f (f held from t = 0), Newmark beta = 1/4, gamma = 1/2.
  const double dt = std::atof(argv[4]), end = std::atof(argv[5]);
  const auto Kr = reduce(stiffness(m, K_u, G), map, nfree);
  Eigen::VectorXd Mfull = Eigen::VectorXd::Zero(static_cast<long>(map.size()));
  const double h = m.h();
  for (int j = 0; j < m.ne; ++j)
    for (int i = 0; i < m.ne; ++i)
      for (int nd : {m.node(i, j), m.node(i + 1, j), m.node(i + 1, j + 1), m.node(i, j + 1)})
        for (int c = 0; c < 2; ++c) Mfull[2 * nd + c] += rho_sat * h * h / 4.0;
  Eigen::VectorXd M(nfree);
  for (std::size_t d = 0; d < map.size(); ++d)
    if (map[d] >= 0) M[map[d]] = Mfull[static_cast<long>(d)];
  Eigen::SparseMatrix<double> A = Kr;
  for (int d = 0; d < nfree; ++d) A.coeffRef(d, d) += 4.0 / (dt * dt) * M[d];
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(nfree), v = u, a = f.cwiseQuotient(M);
  const int steps = static_cast<int>(std::lround(end / dt));
  const int every = std::max(1, static_cast<int>(std::lround(0.005 / dt)));
  const int every_csv = std::max(1, static_cast<int>(std::lround(0.001 / dt)));
  std::FILE* csv = argc > 6 ? std::fopen(argv[6], "w") : nullptr;
  if (csv) {
    std::fprintf(csv,
                 "# A3 strip load, FE dynamic undrained (fe_check.cpp: L = %g m, B = %g m, %d x %d Q1-SRI cells, "
                 "Newmark dt = %g s): u_y at (%g, %g)\n",
                 m.L, m.B, m.ne, m.ne, dt, xm, ym);
    std::fprintf(csv, "time,corner.displacement_y\n0.000,0.0\n");
  }
  std::printf("dynamic undrained, dt = %g s, rho_sat = %g kg/m^3, c_s = %.2f m/s\n", dt, rho_sat,
              std::sqrt(G / rho_sat));
  std::printf("t [s], u_y corner [mm], u_y at (%g, %g) [mm]\n", xm, ym);
  for (int s = 1; s <= steps; ++s) {
    const Eigen::VectorXd rhs = f + (M.array() * (4.0 / (dt * dt) * u + 4.0 / dt * v + a).array()).matrix();
    const Eigen::VectorXd un = solver.solve(rhs);
    const Eigen::VectorXd an = 4.0 / (dt * dt) * (un - u) - 4.0 / dt * v - a;
    v += 0.5 * dt * (a + an);
    a = an;
    u = un;
    if (csv && s % every_csv == 0) std::fprintf(csv, "%.3f,%.6e\n", s * dt, uy_at(m, expand(u, map), xm, ym));
    if (s % every == 0 || s == steps) {
      const Eigen::VectorXd uf = expand(u, map);
      std::printf("%.4f, %.4f, %.4f\n", s * dt, 1e3 * uy_at(m, uf, 0, m.L), 1e3 * uy_at(m, uf, xm, ym));
    }
  }
  if (csv) std::fclose(csv);
  return 0;
}
