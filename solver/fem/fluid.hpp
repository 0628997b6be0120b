// The pore and free fluid of mpm-fem (seed 004, Pan, Yamaguchi, Moriguchi & Terada): Eulerian
// velocity v (the fluid's own, "true" velocity) and pressure p on the grid's B-spline basis, the
// same basis the MPM soil uses, solved together each step by a stabilised finite-element method
// (SUPG / PSPG, Tezduyar 1991, plus the seed's shock-capturing term). docs/formulations.md,
// "mpm-fem", derives every term; the numbers below are the seed's equations.
//
// Strong form on the whole grid (water, air, and the pores of the soil), n the porosity (1 where
// no soil), rho and mu the fluid's blended by the phase field phi (eqs. 89-90):
//   n rho (dv/dt + v.grad v - b) = -n grad p - P^ + div(n mu grad v)       (eq. 9; the viscous
//                                                                           term is ours, below)
//   div((1 - n) v_s + n v) = 0                                             (eq. 14)
//   P^ = theta n^2 (mu / k + 1.75 rho |v - v_s| / (sqrt(150 k) n^(3/2))) (v - v_s)   (eq. 3)
// theta the soil's volume fraction at the node (eq. 79: the drag only where soil is), k the
// intrinsic permeability (Kozeny–Carman, eq. 4), v_s the soil's velocity.
//
// Weak form (eq. 20 with the stabilisation of eq. 25), test functions w (momentum) and q
// (continuity), summed over cells e:
//   int w . n rho (dv/dt + vbar.grad v - b) + int w . P^ - int div(n w) p + int n mu grad w : grad v
//   + int q div((1 - n) v_s + n v)
//   + sum_e int tau_m (vbar.grad w + grad q / rho) . [n rho (dv/dt + vbar.grad v - b) + P^ + n grad p]
//   + sum_e int tau_c rho div w div((1 - n) v_s + n v)  = 0
// with (eqs. 26-29) tau_m = [(2/dt)^2 + (2|vbar|/h)^2 + (4 nu / h^2)^2]^(-1/2),
// tau_c = (h/2) |vbar| xi(Re), Re = |vbar| h / (2 nu), xi = Re/3 (Re <= 3) else 1.
//
// In time (eqs. 58-66): dv/dt = (v^{L+1} - v^L)/dt; v^{L+1/2} = (v^{L+1} + v^L)/2 in the
// momentum balance's advection, viscous and shock-capturing terms; p^{L+1}; v^{L+1} in the
// continuity (theta = 1); v_s^L; P^ at L (explicit drag); vbar = 3/2 v^L - 1/2 v^{L-1}
// (Adams–Bashforth). The system (eqs. 67-68) is linear in (v^{L+1}, p^{L+1}): assembled into a
// fixed pattern (assembly.hpp) and solved by UMFPACK (linear/factorisation.hpp).
//
// Over mpirun's ranks (assembly.hpp's RankShare): each rank assembles an equal share of the cells
// along the grid's last axis and owns the rows of their nodes; the system is solved by MUMPS's
// distributed LU under the same reuse rule (parallel/sparse_solve.hpp), and every rank takes the
// whole solution (the state v, p, phi stays whole on every rank).
//
// Beyond the seed (each measured in docs/formulations.md, "mpm-fem"):
// - the viscous term int n mu grad w : grad v (Laplacian form, theta = 1/2); the seed's weak form
//   has none (mu enters only the drag and tau);
// - tau_c >= h^2 / (4 Dim tau_m): the seed's tau_c vanishes with the speed and leaves a row-to-row
//   velocity mode that the quadratic B-splines' weak continuity does not see;
// - the drag implicit in v^{L+1} (implicit_drag; the seed's explicit drag needs dt < 2 rho k / (n mu));
// - optionally PSPG on the residual's increment over the step (Pspg::increment), which holds
//   hydrostatics across the water-air density jump exactly but does not stabilise steady flows.
#pragma once

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/IterativeLinearSolvers>

#include "solver/common.hpp"
#include "solver/fem/assembly.hpp"
#include "solver/fem/cell_basis.hpp"
#include "solver/grid/grid.hpp"
#include "solver/linear/factorisation.hpp"

namespace swmpm::fem {

/// Water (phi = 1) and air (phi = 0), and the drag law's constants (seed eq. 3).
struct FluidProperties {
  double rho_w = 1000.0, mu_w = 1.0e-3;  // kg/m^3, Pa s
  double rho_a = 1.2, mu_a = 1.8e-5;     // kg/m^3, Pa s
  double kozeny = 150.0;                 // A of k = D^2 n^3 / (A (1 - n)^2)
  double forchheimer = 1.75;             // B of the quadratic drag term
};

/// The soil as the fluid sees it, per node (seed §"Mapping of state variables at node"): porosity
/// n (eq. 81, 1 where no soil), solid volume fraction theta (eq. 79), intrinsic permeability k [m^2]
/// (eq. 78; 0 where no soil), the soil's velocity v_s [m/s] (eq. 77), and its partial density
/// rho_p = (1 - n) rho_s [kg/m^3] (the lumped mass over the node's support; 0 where no soil).
template <int Dim>
struct SoilOnGrid {
  std::vector<double> n, theta, k, rho_p;
  std::vector<Vec<Dim>> vs;
  void resize(std::size_t nodes) {
    n.assign(nodes, 1.0);
    theta.assign(nodes, 0.0);
    rho_p.assign(nodes, 0.0);
    k.assign(nodes, 0.0);
    vs.assign(nodes, Vec<Dim>::Zero());
  }
};

/// What the fields are at one Gauss point.
template <int Dim>
struct FluidPoint {
  double n, theta, k, phi, rho, mu, rho_p;
  Vec<Dim> grad_n, vbar, v, vs;
  MatD<Dim> grad_v;  // (grad v)_ij = d v_i / d x_j, of v^L
  double div_vs;
};

/// The drag coefficient c of P^ = c (v - v_s) (seed eq. 3 with theta): [kg/(m^3 s)].
inline double drag_coefficient(double theta, double n, double k, double mu, double rho, double rel_speed,
                               const FluidProperties& pr) {
  if (!(theta > 0.0) || !(k > 0.0)) return 0.0;
  return theta * n * n * (mu / k + pr.forchheimer * rho * rel_speed / (std::sqrt(pr.kozeny * k) * std::pow(n, 1.5)));
}

template <int Dim, class Shape>
class Fluid {
 public:
  static constexpr int B = Dim + 1;  // unknowns per node: v (Dim), p
  static constexpr int R = Shape::support - 1;
  using Basis = CellBasis<Dim, Shape>;
  static constexpr int K = Basis::K, G = Basis::G;
  using System = NodeSystem<Dim, R, B>;

  /// Per node: bit a set = velocity component a prescribed to 0 (a wall); bit Dim = pressure
  /// prescribed (value in p_value).
  struct Conditions {
    std::vector<std::uint8_t> fixed;
    std::vector<double> p_value;
    /// Per node: -p_bar n_out int N dGamma over faces with a prescribed pressure (N, per unit
    /// porosity): the boundary term of the pressure's integration by parts, times n_I each step.
    std::vector<Vec<Dim>> face_load;
    /// The nodes on faces with a prescribed pressure (open boundaries), for the backflow term.
    struct OpenNode {
      std::size_t node;
      int axis;
      double sign;  // the outward normal is sign e_axis
      double area;  // m (2D, per metre) or m^2: int N_I dGamma over the face
    };
    std::vector<OpenNode> open;
  };

  void setup(const Grid<Dim>& g, const FluidProperties& props, Conditions bcs) {
    grid_ = &g;
    props_ = props;
    bcs_ = std::move(bcs);
    basis_.build(g);
    sys_.build(g);
    const std::size_t nn = g.num_nodes();
    v.assign(nn, Vec<Dim>::Zero());
    v_old.assign(nn, Vec<Dim>::Zero());
    p.assign(nn, 0.0);
    phi.assign(nn, 1.0);
    for (std::size_t i = 0; i < nn; ++i)
      for (int a = 0; a <= Dim; ++a)
        if (bcs_.fixed[i] >> a & 1) sys_.fix(static_cast<long>(i) * B + a, a == Dim ? bcs_.p_value[i] : 0.0);
    x_.setZero(sys_.A.rows());
    refactorise_ = true;  // a new pattern: no factor of it yet
    share_.build(g, sys_.A, ranks_lu_);
    if (!share_.over_ranks) lu_.analyse(sys_.A);
  }

  /// One step (the seed's algorithm step iii, eqs. 67-68): v^{L+1}, p^{L+1} from v^L, v^{L-1},
  /// the soil's fields at L and the body force b [m/s^2]. False when the factorisation or the
  /// solve failed (failure() says why).
  bool step(const SoilOnGrid<Dim>& soil, const Vec<Dim>& b, double dt) {
    assemble(soil, b, dt);
    if (!solve()) return false;
    const std::size_t nn = v.size();
    for (std::size_t i = 0; i < nn; ++i) {
      v_old[i] = v[i];
      for (int a = 0; a < Dim; ++a) v[i][a] = x_[static_cast<long>(i) * B + a];
      p[i] = x_[static_cast<long>(i) * B + Dim];
    }
    return true;
  }

  /// Why the last step's solve failed, in words (the factorisation's reason; "" if it did not fail).
  const std::string& failure() const { return share_.over_ranks ? ranks_lu_.failure() : lu_.failure(); }
  /// Solve statistics (run.json counters, bench/).
  long factorisations() const { return share_.over_ranks ? ranks_lu_.factorisations() : lu_.factorisations(); }
  long krylov_iterations = 0, solves = 0;
  /// The next solve factorises afresh (a checkpoint was taken or restored: a resumed run and the
  /// run that saved then continue with the same factor).
  void refactorise() const { refactorise_ = true; }

  /// The fields at Gauss point gp of cell `c` (v^L, vbar of v^L and v^{L-1}).
  void fields_at(const typename Basis::Cell& c, int gp, const SoilOnGrid<Dim>& soil, FluidPoint<Dim>& f) const {
    f.n = f.theta = f.k = f.phi = f.div_vs = f.rho_p = 0.0;
    f.grad_n.setZero();
    f.vbar.setZero();
    f.v.setZero();
    f.vs.setZero();
    f.grad_v.setZero();
    for (int k = 0; k < K; ++k) {
      const std::size_t i = c.node[k];
      const double N = c.N[gp][k];
      const Vec<Dim>& dN = c.dN[gp][k];
      f.n += N * soil.n[i];
      f.grad_n += soil.n[i] * dN;
      f.theta += N * soil.theta[i];
      f.k += N * soil.k[i];
      f.rho_p += N * soil.rho_p[i];
      f.phi += N * phi[i];
      f.vbar += N * (1.5 * v[i] - 0.5 * v_old[i]);
      f.v += N * v[i];
      f.grad_v.noalias() += v[i] * dN.transpose();
      f.vs += N * soil.vs[i];
      f.div_vs += soil.vs[i].dot(dN);
    }
    const double ph = std::clamp(f.phi, 0.0, 1.0);
    f.rho = props_.rho_w * ph + props_.rho_a * (1.0 - ph);  // eq. 89
    f.mu = props_.mu_w * ph + props_.mu_a * (1.0 - ph);     // eq. 90
    f.theta = std::clamp(f.theta, 0.0, 1.0);
  }

  const Grid<Dim>& grid() const { return *grid_; }
  const Basis& basis() const { return basis_; }
  const FluidProperties& properties() const { return props_; }
  /// The last step's assembled system (A with its prescribed rows, rhs; over ranks this rank's
  /// cells' part of it): bench/fluid_ksp.cpp hands it to PETSc's solvers.
  const System& system() const { return sys_; }
  const Conditions& conditions() const { return bcs_; }

  std::vector<Vec<Dim>> v, v_old;  // m/s, nodal v^L and v^{L-1} (after step: v^{L+1}, v^L)
  std::vector<double> p;           // Pa, nodal pressure (compression positive)
  std::vector<double> phi;         // the phase field's nodal values (PhaseField keeps them current)
  /// What PSPG weights (class comment): the seed's full momentum residual (default) or its
  /// increment over the step.
  enum class Pspg { residual, increment };
  Pspg pspg = Pspg::residual;
  /// The drag P^ = c (v - v_s) with v^{L+1} (true) or v^L (false, the seed's eq. 64-66); c at L.
  bool implicit_drag = true;
  /// The shock-capturing (grad-div) coefficient's floor, in units of h^2 / (4 Dim tau_m) (0: the seed's).
  double min_grad_div = 1.0;
  /// s: the time step in PSPG's tau_m is at least this (0: the seed's eq. 26 as it stands). With
  /// tau_m ~ dt/2 the pressure's stabilisation fades as dt shrinks, and well below the free
  /// surface's own time scale sqrt(h / g) the quadratic B-splines' equal-order pressure shows a
  /// row-to-row mode (the small-time-step weakness of PSPG, Bochev, Gunzburger & Shadid 2004):
  /// a surge of 0.15 m of water over a floor, h = 0.01 m, had a checkerboard indicator of 0.30 at
  /// dt = 0.17 ms (dt = sqrt(h/g) / 190) against 0.03 at 1 ms. A larger tau_p lets the phase
  /// field's blended density drive more flow at the surface of water at rest (1.5e-4 m/s at
  /// floor 0, 2.4e-4 at sqrt(h/g) / 10, 4.8e-4 at sqrt(h/g); test_fem.cpp), so mpm-fem sets the
  /// floor at sqrt(h / |g|) / 40: the surge's indicator 0.03 at 0.17 ms, the water at rest 1.6e-4
  /// m/s. SUPG keeps eq. 26's tau.
  double pspg_time_floor = 0.0;
  /// The continuity takes the skeleton's response to the step's pressure change into account:
  /// the soil moves with p^{L+1} only after the fluid is solved (the seed's staggered steps iii and
  /// v), so the water a moving skeleton displaces is pushed by a pressure the skeleton has not
  /// felt yet. Its inertia is the added mass rho_w (1 - n)^2 / n against the skeleton's own
  /// (1 - n) rho_s, and where the added mass is the larger (n below about rho_w / (rho_w + rho_s),
  /// 0.28 for quartz) the staggered scheme is unstable at any dt: a block with n = 0.1 under water
  /// diverged in 10 steps (n = 0.2 in 20, n = 0.3 in 130; n = 0.4 ran), whatever its permeability,
  /// stiffness or drag treatment (the added-mass instability of partitioned fluid-structure
  /// coupling, Causin, Gerbeau & Nobile 2005). The skeleton's velocity change from a pressure
  /// change dp, with its drag implicit, is -dt (1 - n) grad dp / ((1 - n) rho_s + dt c); its
  /// divergence in the continuity adds
  ///   + int kappa_s grad q . grad (p^{L+1} - p^L),   kappa_s = dt (1 - n)^2 / ((1 - n) rho_s + dt c)
  /// (the p^L part on the right-hand side), which vanishes in a steady state and where no soil is
  /// (a fixed-stress-like split).
  bool soil_response = true;
  double seconds_assemble = 0.0, seconds_factorise = 0.0, seconds_solve = 0.0;

 private:
  void assemble(const SoilOnGrid<Dim>& soil, const Vec<Dim>& b, double dt) {
    const double t0 = omp_get_wtime();
    const auto [first, last] = share_.unknowns();
    sys_.clear(first, last);
    const double h = grid_->h();
    const int threads = omp_get_max_threads();
    if (static_cast<int>(local_.size()) < threads) local_.resize(threads);
    double* rhs = sys_.rhs.data();
    for_each_cell_coloured<Dim, Shape::support>(share_.cell_lo, share_.cell_hi, [&](const std::array<int, Dim>& cell) {
      Local& L = local_[omp_get_thread_num()];
      basis_.eval(cell, L.c);
      // Per Gauss point g (a column) and function k (a row), the factors of every term, so that each
      // block of the cell's matrix is a sum of products (K x G)(G x K) (see the class comment):
      //   Wt   w (N_a + s_a)         SUPG-weighted test       T    (n rho (1/dt + 1/2 vbar.grad) + c) N_b
      //   Nt   w N_a                 Galerkin test            Nm   N_b
      //   Ct_i w C_a,i, C = n grad N + N grad n (the divergence of n N)
      //   Vt_i w 1/2 mu n d_i N_a    viscous                  Dm_i d_i N_b
      //   Lt_i w 1/2 tau_c rho d_i N_a   grad-div             Cm_i C_b,i
      //   St   w s_a n               SUPG on n grad p         Pt_i w (tau / rho) d_i N_a (PSPG)
      //   nD_i n d_i N_b
      auto& M = L.m;
      bool soil_cell = false;  // a Gauss point with kappa_s > 0: the skeleton's response is assembled
      FluidPoint<Dim> f;
      for (int gp = 0; gp < G; ++gp) {
        fields_at(L.c, gp, soil, f);
        const double w = L.c.JxW[gp];
        const double nu = f.mu / f.rho, speed = f.vbar.norm();
        const double steady = 4.0 * speed * speed / (h * h) + 16.0 * nu * nu / (h * h * h * h);
        const double tau = 1.0 / std::sqrt(4.0 / (dt * dt) + steady);  // eq. 26

        const double Re = speed * h / (2.0 * nu);                                // eq. 28
        // eqs. 27, 29; at least h^2 / (4 Dim tau_m) (Bazilevs et al. 2007's tau_C on this grid): the
        // seed's vanishes with the speed, and a slow through-flow kept a row-to-row velocity mode of
        // +-13 % that the quadratic B-splines' weak continuity does not see (docs/formulations.md).
        const double tau_c = std::max(0.5 * h * speed * (Re <= 3.0 ? Re / 3.0 : 1.0), min_grad_div * h * h / (4.0 * Dim * tau));
        const double W = f.n * f.rho;
        const Vec<Dim> rel = f.v - f.vs;
        const double cd = drag_coefficient(f.theta, f.n, f.k, f.mu, f.rho, rel.norm(), props_);
        // PSPG's tau: eq. 26 with dt no smaller than pspg_time_floor (see there), and then with the
        // drag's rate c / (n rho) beside the others, so that the floor never makes tau_p longer
        // than the time the drag takes to lock the water to the skeleton (without it, a column of
        // 0.225 mm beads in 12 mPa s fluid diverged in 30 steps at any dt: tau_p c / (n rho) ~ 6).
        const double dt_p = std::max(dt, pspg_time_floor);
        const double tau_p = dt_p > dt ? 1.0 / std::sqrt(4.0 / (dt_p * dt_p) + steady + cd * cd / (W * W)) : tau;
        const double cdi = implicit_drag ? cd : 0.0;
        // The skeleton's response to this step's pressure change (see soil_response):
        // kappa_s = dt (1 - n)^2 / ((1 - n) rho_s + dt c)  [m^3 s / kg].
        const double kappa_s = soil_response && f.rho_p > 0.0 ? dt * (1.0 - f.n) * (1.0 - f.n) / (f.rho_p + dt * cd) : 0.0;
        soil_cell = soil_cell || kappa_s > 0.0;
        // The residual's explicit part r = n rho (v^L/dt - 1/2 vbar.grad v^L + b) - P^(L); with
        // the drag implicit, P^ = c (v^{L+1} - v_s^L) (c at L): c v_s^L here, c N_b on the left.
        const Vec<Dim> r = W * (f.v / dt - 0.5 * f.grad_v * f.vbar + b) - (implicit_drag ? Vec<Dim>(-cd * f.vs) : Vec<Dim>(cd * rel));
        // PSPG's explicit part: the seed's full residual r (default), or its increment over the
        // step (Pspg::increment: the static part at L, n grad p^L - n rho b + P^(L), subtracted;
        // + c v^L with the drag implicit, whose c v^{L+1} is on the left; see the class comment).
        Vec<Dim> static_part = Vec<Dim>::Zero();
        if (pspg == Pspg::increment)
          for (int k = 0; k < K; ++k) static_part += (f.n * p[L.c.node[k]]) * L.c.dN[gp][k];
        const Vec<Dim> r_pspg =
            pspg == Pspg::residual ? r : Vec<Dim>(W * (f.v / dt - 0.5 * f.grad_v * f.vbar) + cdi * f.v + static_part);
        const double div_nv = f.n * f.grad_v.trace() + f.grad_n.dot(f.v);     // div(n v^L)
        const double div_svs = (1.0 - f.n) * f.div_vs - f.grad_n.dot(f.vs);  // div((1 - n) v_s)
        const double visc = 0.5 * f.mu * f.n, lsic = 0.5 * tau_c * f.rho, pspg_w = tau_p / f.rho;
        for (int k = 0; k < K; ++k) {
          const double N = L.c.N[gp][k];
          const Vec<Dim>& dN = L.c.dN[gp][k];
          const double ugN = f.vbar.dot(dN);
          M.Nm(k, gp) = N;
          M.Nt(k, gp) = w * N;
          M.Wt(k, gp) = w * (N + tau * ugN);
          M.T(k, gp) = W * (N / dt + 0.5 * ugN) + cdi * N;
          M.St(k, gp) = w * tau * ugN * f.n;
          for (int d = 0; d < Dim; ++d) {
            const double C = f.n * dN[d] + f.grad_n[d] * N;
            M.Dm[d](k, gp) = dN[d];
            M.nD[d](k, gp) = f.n * dN[d];
            M.Cm[d](k, gp) = C;
            M.Ct[d](k, gp) = w * C;
            M.Vt[d](k, gp) = w * visc * dN[d];
            M.Lt[d](k, gp) = w * lsic * dN[d];
            M.Pt[d](k, gp) = w * pspg_w * dN[d];
            M.St_s[d](k, gp) = w * kappa_s * dN[d];
          }
        }
        // right-hand sides per g: the momentum's (N_a + s_a) r_i - 1/2 mu n grad N_a . grad v_i^L -
        // tau_c rho d_i N_a (1/2 div(n v^L) + div((1 - n) v_s)); the continuity's
        // -N_a div((1 - n) v_s) + pi_a . r_pspg
        Vec<Dim> grad_p_old = Vec<Dim>::Zero();
        if (kappa_s > 0.0)
          for (int k = 0; k < K; ++k) grad_p_old += p[L.c.node[k]] * L.c.dN[gp][k];
        for (int d = 0; d < Dim; ++d) {
          M.gp_old(d, gp) = grad_p_old[d];
          M.r(d, gp) = r[d];
          M.rp(d, gp) = r_pspg[d];
          M.gv[d].col(gp) = f.grad_v.row(d).transpose();
        }
        M.gd(gp) = 0.5 * div_nv + div_svs;
        M.svs(gp) = div_svs;
      }
      // The blocks (rows a, columns b): momentum i / velocity j, momentum i / pressure,
      // continuity / velocity j, continuity / pressure.
      const typename Local::MatKK diag = M.Wt.lazyProduct(M.T.transpose()) + [&] {
        typename Local::MatKK vis = Local::MatKK::Zero();
        for (int d = 0; d < Dim; ++d) vis.noalias() += M.Vt[d].lazyProduct(M.Dm[d].transpose());
        return vis;
      }();
      typename Local::MatKK pp = Local::MatKK::Zero();
      for (int d = 0; d < Dim; ++d) {
        pp.noalias() += M.Pt[d].lazyProduct(M.nD[d].transpose());
        if (soil_cell) pp.noalias() += M.St_s[d].lazyProduct(M.Dm[d].transpose());
      }
      for (int i = 0; i < Dim; ++i) {
        for (int j = 0; j < Dim; ++j) {
          typename Local::MatKK blk = M.Lt[i].lazyProduct(M.Cm[j].transpose());
          if (i == j) blk += diag;
          put_block(L, i, j, blk);
        }
        put_block(L, i, Dim, -M.Ct[i].lazyProduct(M.Nm.transpose()) + M.St.lazyProduct(M.Dm[i].transpose()));
        put_block(L, Dim, i, M.Nt.lazyProduct(M.Cm[i].transpose()) + M.Pt[i].lazyProduct(M.T.transpose()));
      }
      put_block(L, Dim, Dim, pp);
      for (int i = 0; i < Dim; ++i) {
        Eigen::Matrix<double, K, 1> fi = M.Wt * M.r.row(i).transpose() - M.Lt[i] * M.gd * 2.0;
        for (int d = 0; d < Dim; ++d) fi -= M.Vt[d] * M.gv[i].row(d).transpose();
        for (int k = 0; k < K; ++k) L.fe[k * B + i] = fi[k];
      }
      {
        Eigen::Matrix<double, K, 1> fp = -M.Nt * M.svs;
        for (int d = 0; d < Dim; ++d) {
          fp += M.Pt[d] * M.rp.row(d).transpose();
          if (soil_cell) fp += M.St_s[d] * M.gp_old.row(d).transpose();
        }
        for (int k = 0; k < K; ++k) L.fe[k * B + Dim] = fp[k];
      }
      sys_.template add_cell<Shape::support>(L.c.node, &L.Ae[0][0], L.fe);  // this colour's cells share no node
    });
    // Backflow stabilisation on open faces (Bazilevs, Gohean, Hughes, Moser & Zhang 2009, their
    // eq. 4 with beta = 1, lumped at the face's nodes): where the fluid enters through a face
    // with a prescribed pressure, vbar.n_out < 0, the convective term's boundary flux
    // 1/2 rho (v.n) |v|^2 would bring in kinetic energy that nothing bounds (the air sucked in
    // through the open top behind a falling water jet ran away to 255 m/s in 0.035 s); the term
    // -int rho n {vbar.n}_- w.v^{L+1} dGamma takes it out again and vanishes on outflow.
    // Node terms: the owner of the node's rows adds them.
    for (const auto& o : bcs_.open) {
      const std::size_t i = o.node;
      if (!share_.owns(i)) continue;
      const double un = o.sign * (1.5 * v[i][o.axis] - 0.5 * v_old[i][o.axis]);
      if (!(un < 0.0)) continue;
      const double rho = props_.rho_a + std::clamp(phi[i], 0.0, 1.0) * (props_.rho_w - props_.rho_a);
      for (int a = 0; a < Dim; ++a) sys_.add_diagonal(i, a, soil.n[i] * rho * (-un) * o.area);
    }
    for (std::size_t i = 0; i < bcs_.face_load.size(); ++i)
      if (share_.owns(i) && bcs_.face_load[i].squaredNorm() > 0.0)
        for (int a = 0; a < Dim; ++a) rhs[static_cast<long>(i) * B + a] += soil.n[i] * bcs_.face_load[i][a];
    sys_.apply_fixed(1.0, static_cast<long>(share_.own_lo) * B, static_cast<long>(share_.own_hi) * B, first, last);
    seconds_assemble += omp_get_wtime() - t0;
  }

  /// The last LU factor as the preconditioner of BiCGSTAB (Eigen's preconditioner interface):
  /// the matrix changes little from step to step (phi, the advection velocity, the soil), so an
  /// old factor solves the new system in a few iterations. The system is factorised afresh on the
  /// first step, when the previous step's solve took kRefactoriseAfter iterations or more (the
  /// factor has aged: waiting for a failure wastes kMaxReuseIterations iterations, each two LU
  /// solves), and when a solve fails. The rule counts iterations, never seconds, so that threads
  /// and restarts reproduce the run bit for bit. Measured on the dam break (60 steps of 1 ms,
  /// 2,160 nodes, 1 thread): fail-only with tolerance 1e-10 took 3.56 s (15 factorisations, 6.3
  /// iterations a step); after 5 iterations with 1e-8, 2.75 s (18, 2.9).
  struct FactorPreconditioner {
    const linear::LU* lu = nullptr;
    template <class M>
    FactorPreconditioner& analyzePattern(const M&) { return *this; }
    template <class M>
    FactorPreconditioner& factorize(const M&) { return *this; }
    template <class M>
    FactorPreconditioner& compute(const M&) { return *this; }
    template <class Rhs>
    Eigen::VectorXd solve(const Rhs& r) const {
      const Eigen::VectorXd rr = r;
      Eigen::VectorXd z;
      lu->solve(rr, z);
      return z;
    }
    Eigen::ComputationInfo info() const { return Eigen::Success; }
  };
  static constexpr int kMaxReuseIterations = 10;
  static constexpr int kRefactoriseAfter = 5;
  static constexpr double kTolerance = 1e-8;  // relative residual of the Krylov solve

  bool solve() {
    ++solves;
    if (share_.over_ranks) share_.values(sys_.A, sys_.rhs, values_, b_values_);
    if (factorisations() > 0 && !refactorise_ && last_iterations_ < kRefactoriseAfter) {
      int iterations = 0;
      const bool ok = reuse_factor(iterations);
      krylov_iterations += iterations;
      last_iterations_ = iterations;
      if (ok) return true;
    }
    refactorise_ = false;
    last_iterations_ = 0;
    return factorise_and_solve();
  }

  /// BiCGSTAB from the last solution, preconditioned by the kept factor: UMFPACK's (Eigen's
  /// BiCGSTAB) or, over the ranks, MUMPS's (PETSc's). False, x_ unchanged, if it did not converge.
  bool reuse_factor(int& iterations) {
    const double t0 = omp_get_wtime();
    bool ok = false;
    if (share_.over_ranks) {
      const auto s = ranks_lu_.solve(values_, b_values_, false, kTolerance, kMaxReuseIterations, x_all_);
      iterations = s.iterations;
      ok = s.ok;
      if (ok) x_ = Eigen::Map<const Eigen::VectorXd>(x_all_.data(), static_cast<long>(x_all_.size()));
    } else {
      Eigen::BiCGSTAB<linear::CscMatrix, FactorPreconditioner> krylov;
      krylov.preconditioner().lu = &lu_;
      krylov.setTolerance(kTolerance);
      krylov.setMaxIterations(kMaxReuseIterations);
      krylov.compute(sys_.A);
      Eigen::VectorXd x = krylov.solveWithGuess(sys_.rhs, x_);
      iterations = static_cast<int>(krylov.iterations());
      ok = krylov.info() == Eigen::Success && x.allFinite();
      if (ok) x_ = std::move(x);
    }
    seconds_solve += omp_get_wtime() - t0;
    return ok;
  }

  /// A fresh factor of A (UMFPACK's, or over the ranks MUMPS's) and x = A^-1 b by it alone.
  bool factorise_and_solve() {
    if (share_.over_ranks) {
      const auto s = ranks_lu_.solve(values_, b_values_, true, kTolerance, kMaxReuseIterations, x_all_);
      seconds_factorise += s.seconds_factorise;
      seconds_solve += s.seconds_solve;
      if (s.ok) x_ = Eigen::Map<const Eigen::VectorXd>(x_all_.data(), static_cast<long>(x_all_.size()));
      return s.ok;
    }
    const double t0 = omp_get_wtime();
    if (!lu_.factorise(sys_.A)) return false;
    const double t1 = omp_get_wtime();
    seconds_factorise += t1 - t0;
    const bool ok = lu_.solve(sys_.rhs, x_);
    seconds_solve += omp_get_wtime() - t1;
    return ok && x_.allFinite();
  }

  struct Local {
    using MatKG = Eigen::Matrix<double, K, G>;
    using MatKK = Eigen::Matrix<double, K, K>;
    using MatDG = Eigen::Matrix<double, Dim, G>;
    struct Factors {
      MatKG Nm, Nt, Wt, T, St;
      std::array<MatKG, Dim> Dm, nD, Cm, Ct, Vt, Lt, Pt, St_s;
      MatDG r, rp, gp_old;  // gp_old: grad p^L
      std::array<MatDG, Dim> gv;  // (grad v^L)_i. at each g, i the row
      Eigen::Matrix<double, G, 1> gd, svs;
    };
    typename Basis::Cell c;
    Factors m;
    double Ae[K * B][K * B];
    double fe[K * B];
  };
  /// Block (unknown a of every row node, unknown b of every column node) of the cell's matrix.
  static void put_block(Local& L, int a, int b, const typename Local::MatKK& blk) {
    for (int kb = 0; kb < K; ++kb)
      for (int ka = 0; ka < K; ++ka) L.Ae[ka * B + a][kb * B + b] = blk(ka, kb);
  }

  const Grid<Dim>* grid_ = nullptr;
  FluidProperties props_;
  Conditions bcs_;
  Basis basis_;
  System sys_;
  linear::LU lu_;
  Eigen::VectorXd x_;
  std::vector<Local> local_;
  mutable bool refactorise_ = false;
  int last_iterations_ = 0;
  RankShare<Dim, Shape::support, B> share_;  // one rank's whole grid, or this rank's share over ranks
  parallel::SparseSolve ranks_lu_{parallel::SparseSolve::Preconditioner::lu};
  std::vector<double> values_, b_values_, x_all_;
};

}  // namespace swmpm::fem
