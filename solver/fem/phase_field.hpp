// The free surface of mpm-fem: an Allen–Cahn phase field phi (1 water, 0 air; seed 004 App. B,
// after Jacqmin 1999 and Takada et al. 2016) on the grid's B-spline basis, advected by the fluid's
// velocity and stabilised by SUPG and the seed's LSIC term:
//
//   dphi/dt + v.grad phi = M_phi (a^2 lap phi + 4 W phi (1 - phi)(phi - 1/2))       (eqs. 91-92)
//
// weak form (eq. 94), tau_phi = [(2/dt)^2 + (2|v|/h)^2]^(-1/2), tau_LSIC = (h/2)|v| (eqs. 95-96):
//   int psi (dphi/dt + v.grad phi) + M a^2 int grad psi.grad phi - 4 W M int psi f(phi)
//   + sum_e int tau_phi v.grad psi (dphi/dt + v.grad phi - 4 W M f(phi))
//   + sum_e int tau_LSIC grad psi.grad phi = 0,          f(phi) = phi (1 - phi)(phi - 1/2)
// in time as eq. 106: Crank–Nicolson on the linear terms, f(phi^L) explicit.
//
// The planar equilibrium is phi = (1 + tanh(x / delta)) / 2 with delta = a sqrt(2 / W): it rises
// from 0.05 to 0.95 over 2 atanh(0.9) delta = 2.944 delta, the scene's `interface_width`. Only
// delta and the relaxation rate M W matter; W = 1 here and a follows from the width. The
// interface relaxes at the rate M W (1/s), and a curved interface moves at M a^2 kappa: a high
// mobility keeps the interface sharp but pulls a thin surge front back (docs/formulations.md: the
// dam break). The seed's LSIC term, (h/2)|v| grad psi . grad phi, is off by default (`lsic`): it
// smeared the dam break's front, which fell 16 % behind Martin & Moyce.
//
// Allen–Cahn moves a curved interface at the normal speed M a^2 kappa, which loses water where
// the surface is convex. The water volume int n phi is restored after each step by a correction
// concentrated in the interface, phi += lambda 4 phi (1 - phi), lambda making int n phi the
// caller's target (a Lagrange multiplier in the spirit of Brassel & Bretin 2011), when
// `volume_correction`. mpm-fem's target is the initial volume less what left through open faces:
// advected by the intrinsic velocity, phi conserves int n phi only as far as the discrete
// mixture continuity matches the moving porosity, and a column collapsing into water lost 12.7 %
// when each step only restored its own start.
//
// Over mpirun's ranks each rank assembles its share of the cells (assembly.hpp's RankShare)
// and PETSc's BiCGSTAB with the diagonal solves the system (parallel/sparse_solve.hpp); every rank
// takes the whole phi, and the volume correction runs whole on every rank.
#pragma once

#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <cmath>
#include <vector>

#include "solver/common.hpp"
#include "solver/fem/assembly.hpp"
#include "solver/fem/cell_basis.hpp"
#include "solver/grid/grid.hpp"

namespace swmpm::fem {

struct PhaseFieldParameters {
  double width = 0.0;     // m, the 5 %-95 % interface width (2.944 delta)
  double mobility = 0.0;  // M_phi, with W = 1: the relaxation rate (1/s)
  bool volume_correction = true;
  bool lsic = false;  // the seed's LSIC diffusion (h/2)|v| (eq. 96)
  double delta() const { return width / (2.0 * std::atanh(0.9)); }
  double a2() const { return 0.5 * delta() * delta(); }  // a^2 = delta^2 W / 2, W = 1
};

template <int Dim, class Shape>
class PhaseField {
 public:
  static constexpr int R = Shape::support - 1;
  using Basis = CellBasis<Dim, Shape>;
  static constexpr int K = Basis::K, G = Basis::G;
  using System = NodeSystem<Dim, R, 1>;

  void setup(const Grid<Dim>& g, const Basis& basis, const PhaseFieldParameters& prm) {
    grid_ = &g;
    basis_ = &basis;
    prm_ = prm;
    sys_.build(g);
    x_.setZero(sys_.A.rows());
    share_.build(g, sys_.A, ranks_solve_);
  }

  /// phi^{L+1} from phi^L (in place) with the fluid's nodal velocity v and the nodal porosity n
  /// (the volume correction's weight). The correction brings int n phi to `target` (m^Dim), or,
  /// with a negative target, back to its value before the step. Returns the BiCGSTAB iterations
  /// (-1: no convergence).
  int step(std::vector<double>& phi, const std::vector<Vec<Dim>>& v, const std::vector<double>& n, double dt,
           double target = -1.0) {
    const double V0 = target >= 0.0 ? target : volume(phi, n);
    assemble(phi, v, dt);
    int iterations = 0;
    if (share_.over_ranks) {  // this rank's cells assembled: PETSc's BiCGSTAB with the diagonal (sparse_solve.hpp)
      share_.values(sys_.A, sys_.rhs, values_, b_values_);
      const auto s = ranks_solve_.solve(values_, b_values_, false, kTolerance, kMaxIterations, x_all_, phi.data());
      if (!s.ok) return -1;
      phi = x_all_;
      iterations = s.iterations;
    } else {
      Eigen::BiCGSTAB<linear::CscMatrix, Eigen::DiagonalPreconditioner<double>> solver;
      solver.setTolerance(kTolerance);
      solver.setMaxIterations(kMaxIterations);
      solver.compute(sys_.A);
      x_ = solver.solveWithGuess(sys_.rhs, Eigen::Map<const Eigen::VectorXd>(phi.data(), static_cast<long>(phi.size())));
      if (solver.info() != Eigen::Success) return -1;
      for (std::size_t i = 0; i < phi.size(); ++i) phi[i] = x_[static_cast<long>(i)];
      iterations = static_cast<int>(solver.iterations());
    }
    if (prm_.volume_correction) correct_volume(phi, n, V0);
    return iterations;
  }

  /// int n phi dOmega (m^Dim): the water's volume (n = 1 outside soil).
  double volume(const std::vector<double>& phi, const std::vector<double>& n) const {
    double V = 0.0;
    for_each_cell_serial([&](const typename Basis::Cell& c) {
      for (int gp = 0; gp < G; ++gp) {
        double ph = 0.0, nn = 0.0;
        for (int k = 0; k < K; ++k) {
          ph += c.N[gp][k] * phi[c.node[k]];
          nn += c.N[gp][k] * n[c.node[k]];
        }
        V += c.JxW[gp] * nn * ph;
      }
    });
    return V;
  }

  /// The last step's assembled system (over ranks: this rank's cells' part of it).
  const System& system() const { return sys_; }

  double last_correction = 0.0;  // the last step's lambda
  double last_corrected_volume = 0.0;  // m^Dim: what the last step's correction added to int n phi

 private:
  template <class Fn>
  void for_each_cell_serial(Fn&& fn) const {
    typename Basis::Cell c;
    std::array<int, Dim> cell{};
    const NodeBox<Dim> all = cells_box();
    grid_->for_each_node(all, [&](std::size_t, const std::array<int, Dim>& ijk) {
      cell = ijk;
      basis_->eval(cell, c);
      fn(c);
    });
  }
  NodeBox<Dim> cells_box() const {
    NodeBox<Dim> b;
    for (int a = 0; a < Dim; ++a) {
      b.lo[a] = 0;
      b.hi[a] = grid_->axis(a).cells - 1;
    }
    return b;
  }

  /// phi += lambda 4 phi (1 - phi) at the nodes, lambda from int n phi = V0 to first order.
  void correct_volume(std::vector<double>& phi, const std::vector<double>& n, double V0) {
    std::vector<double>& g = weight_;
    g.resize(phi.size());
    for (std::size_t i = 0; i < phi.size(); ++i) {
      const double p = std::clamp(phi[i], 0.0, 1.0);
      g[i] = 4.0 * p * (1.0 - p);
    }
    const double V = volume(phi, n), dV = volume(g, n);
    if (!(dV > 0.0)) return;
    last_correction = (V0 - V) / dV;
    last_corrected_volume = V0 - V;
    for (std::size_t i = 0; i < phi.size(); ++i) phi[i] += last_correction * g[i];
  }

  void assemble(const std::vector<double>& phi, const std::vector<Vec<Dim>>& v, double dt) {
    const auto [first, last] = share_.unknowns();
    sys_.clear(first, last);
    const double h = grid_->h(), M = prm_.mobility, Ma2 = M * prm_.a2(), react = 4.0 * M;  // W = 1
    const int threads = omp_get_max_threads();
    if (static_cast<int>(local_.size()) < threads) local_.resize(threads);
    for_each_cell_coloured<Dim, Shape::support>(share_.cell_lo, share_.cell_hi, [&](const std::array<int, Dim>& cell) {
      Local& L = local_[omp_get_thread_num()];
      basis_->eval(cell, L.c);
      std::fill(&L.Ae[0][0], &L.Ae[0][0] + K * K, 0.0);
      std::fill(L.fe, L.fe + K, 0.0);
      for (int gp = 0; gp < G; ++gp) {
        double ph = 0.0;
        Vec<Dim> u = Vec<Dim>::Zero(), gph = Vec<Dim>::Zero();
        for (int k = 0; k < K; ++k) {
          const std::size_t i = L.c.node[k];
          ph += L.c.N[gp][k] * phi[i];
          u += L.c.N[gp][k] * v[i];
          gph += phi[i] * L.c.dN[gp][k];
        }
        const double w = L.c.JxW[gp], speed = u.norm();
        const double tau = 1.0 / std::sqrt(4.0 / (dt * dt) + 4.0 * speed * speed / (h * h));  // eq. 95
        const double tau_ls = prm_.lsic ? 0.5 * h * speed : 0.0;  // eq. 96 (off by default, see the comment above)
        const double f = react * ph * (1.0 - ph) * (ph - 0.5);  // 4 W M f(phi^L)
        double ugN[K];
        for (int k = 0; k < K; ++k) ugN[k] = u.dot(L.c.dN[gp][k]);
        const double ugphi = u.dot(gph);
        for (int ka = 0; ka < K; ++ka) {
          const double Na = L.c.N[gp][ka], wa = Na + tau * ugN[ka];
          const Vec<Dim>& dNa = L.c.dN[gp][ka];
          for (int kb = 0; kb < K; ++kb) {
            const double Nb = L.c.N[gp][kb];
            const double diff = (Ma2 + tau_ls) * dNa.dot(L.c.dN[gp][kb]);
            L.Ae[ka][kb] += w * (wa * (Nb / dt + 0.5 * ugN[kb]) + 0.5 * diff);
          }
          // right-hand side: (M + M_s) phi^L / dt - 1/2 (A + A_s + D + S_c) phi^L + P + P_s
          double ph_a = 0.0;
          ph_a = wa * (ph / dt - 0.5 * ugphi + f) - 0.5 * (Ma2 + tau_ls) * dNa.dot(gph);
          L.fe[ka] += w * ph_a;
        }
      }
      sys_.template add_cell<Shape::support>(L.c.node, &L.Ae[0][0], L.fe);  // this colour's cells share no node
    });
  }

  struct Local {
    typename Basis::Cell c;
    double Ae[K][K];
    double fe[K];
  };

  static constexpr double kTolerance = 1e-10;  // BiCGSTAB's relative residual
  static constexpr int kMaxIterations = 500;

  const Grid<Dim>* grid_ = nullptr;
  const Basis* basis_ = nullptr;
  PhaseFieldParameters prm_;
  System sys_;
  RankShare<Dim, Shape::support, 1> share_;  // one rank's whole grid, or this rank's share over ranks
  parallel::SparseSolve ranks_solve_{parallel::SparseSolve::Preconditioner::jacobi};
  std::vector<double> values_, b_values_, x_all_;
  Eigen::VectorXd x_;
  std::vector<Local> local_;
  std::vector<double> weight_;
};

}  // namespace swmpm::fem
