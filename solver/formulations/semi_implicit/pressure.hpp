// The pressure step of the semi-implicit formulations (seed 001 steps 5-6, eqs. 60-68, 77), in
// swmpm's signs (docs/formulations.md): the operators D^s, D^w and L, the nodal p^t and the
// prescribed nodes (drained faces, free surface), the Poisson solve for the increment dp, the
// strong-gradient pressure force G q of the predictor and the corrections, and p^{t+1} at the
// water's points. Both variants use it; they differ only in which points carry the water (the
// set, shape data and schedule passed in).
//
//   dt sum_J L_IJ dp_J = -(D^s v_s* + D^w v_w*)_I   (eq. 60, (5c)), with
//   D^s_IK = sum_sp (1 - n) V S_I grad S_K,  D^w_IK = sum_wp n V S_I grad S_K   (eqs. 62-63)
//   L_IJ = sum_p V c_p grad S_I . grad S_J,  c = (1 - n)/rho_s (soil) + n/rho_w (water)  (eq. 61,
//   c inside the quadrature: L symmetric, CHOLMOD)
// The pressure forces and the corrections use G = D read as (velocity node, pressure node): the
// strong gradient of eqs. 67-68. The exact projection D M^-1 D^T in place of L was tried (with
// the weak gradient D^T): stable, but its two-cell stencil decouples the pressure (Terzaghi on
// GIMP 30 % RMS error instead of 0.09 %).
#pragma once

#include <algorithm>
#include <array>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

#include "solver/formulations/semi_implicit/pressure_poisson.hpp"
#include "solver/grid/grid.hpp"
#include "solver/output/checkpoint.hpp"
#include "solver/parallel/domain.hpp"
#include "solver/parallel/poisson.hpp"
#include "solver/porous/free_surface.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/cell_moments.hpp"
#include "solver/transfer/projection.hpp"
#include "solver/transfer/schedule.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm::semi_implicit {

/// The p^t at the points from which p^{t+1} = p^t + sum S dp starts (solver.stabilisation.pressure):
/// `none` the point's own; `node-remap` sum S pbar_I, pbar_I the water-mass-weighted nodal
/// average (eq. 77); `mfvp-linear` the same with the linear projection (reproduces linear fields).
enum class Remap { none, node, linear };

/// A point's weights in the operators of (5a): D^s gets s = (1 - n) V, D^w gets w = n V, L gets
/// l = c V with c = (1 - n)/rho_s + n/rho_w (each variant gives its points' shares).
struct Weights {
  double s, w, l;
};

template <int Dim, class Shape>
class PressureStep {
  static constexpr int S = Shape::support;

 public:
  using Poisson = PressurePoisson<Dim, S - 1>;  // rows of L reach S - 1 nodes per axis
  using DSt = linear::Stencil<Dim, S - 1>;               // so do those of D
  static constexpr int KD = DSt::K;
  static constexpr int NP = Dim == 2 ? S * S : S * S * S;  // nodes per point
  /// 2D with a shape function that is one polynomial per cell (linear, B-splines): the operators
  /// are assembled from cell moments (transfer/cell_moments.hpp). GIMP and 3D scatter point by point.
  static constexpr bool kCellMoments = Dim == 2 && (Shape::bspline || std::is_same_v<Shape, shape::Linear>);
  using Moments = transfer::CellMoments<std::conditional_t<kCellMoments, Shape, shape::Linear>>;

  /// Under mpirun the per-node stages read their neighbours up to kGhost node columns beyond the
  /// rank's own (G p at the top shared column reaches R = S - 1 further; the fit's inward search
  /// as far): the ghost columns, which Domain::fill_ghosts fills from their owners.
  static constexpr int kGhost = 2 * (S - 1);

  /// face_drained[f]: the water drains through grid face f (p prescribed: face_pressure[f], Pa).
  /// box: the step's nodes (the formulation's; under mpirun the rank's own and shared columns);
  /// reach: the nodes whose values may be read (box at one rank; with the ghost columns under mpirun).
  PressureStep(const Grid<Dim>& g, const NodeBox<Dim>& box, const NodeBox<Dim>& reach, Remap remap,
               const std::array<bool, 6>& face_drained, const std::array<double, 6>& face_pressure)
      : grid_(g), box_(box), reach_(reach), remap_(remap), face_drained_(face_drained), face_pressure_(face_pressure),
        poisson_(g), surface_(g.num_nodes()) {
    const std::size_t nodes = g.num_nodes();
    p_node_.resize(nodes);  // zero (NodeArray: memory only where the steps' boxes reach)
    D_solid_.resize(nodes * KD);
    D_water_.resize(nodes * KD);
    if constexpr (kCellMoments) moments_ = std::make_unique<Moments>(g);
    d_steps_ = DSt::steps(g.nodes_per_axis());
  }

  /// Under mpirun: the decomposition whose ghost columns the stages fill, and the distributed
  /// solve of (5c) in place of CHOLMOD (parallel::GridPoisson). Nothing at one rank.
  void distribute(const parallel::Domain<Dim>& d) {
    if (d.active()) domain_ = &d;
  }
  /// The ghost columns of a node array, filled from their owners (nothing at one rank). Collective.
  template <class Array>
  void fill_ghosts(Array&& a) const {
    if (domain_) domain_->fill_ghosts(a, kGhost);
  }

  /// The water's extent per node, for the free surface (the P2G passes add to it).
  porous::SupportCut<Dim, Shape>& surface() { return surface_; }
  /// The points' moments of (5a) (kCellMoments; the P2G passes add to them).
  Moments& moments() { return *moments_; }
  bool laplace_derived() const { return kCellMoments && moments_->laplace_derived(); }
  Remap remap() const { return remap_; }
  const NodeArray<double>& p_node() const { return p_node_; }
  const NodeArray<double>& dp() const { return poisson_.dp(); }
  /// p^t at node i from the linear projection of the points' pressures.
  double p_at_node(std::size_t i) const { return linear_.at_node(i); }
  bool drained(int f) const { return face_drained_[f]; }
  double face_pressure(int f) const { return face_pressure_[f]; }

  /// (5b) p^t at the nodes: the linear projection of the water's points' pressures, weight(p)
  /// the point's volume (0 for a point without water: a dry single-point point). A node whose water lies in a strip of its support (free surface) has an ill-posed
  /// linear fit (leverage > NodeProjection::kMaxLeverage): it takes the gradient of the nearest
  /// well-posed node inward along its cut and fits only its value (docs/formulations.md,
  /// "Free-surface nodes whose fit is ill-posed"). Reads well-posed nodes only, writes its own:
  /// independent of the node order.
  template <class SD, class Weight>
  void fit(const StripeSchedule& schedule, const std::vector<SD>& sd, const ParticleSet<Dim>& ws, Weight&& weight) {
    linear_.fit(grid_, box_, schedule, sd, ws.x, weight, [&](int p) { return ws.p[p]; });
    linear_.for_each_node_array([&](auto& a) { fill_ghosts(a); });  // mpirun: the inward search reads them
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto& ijk) {
      if (!linear_.has(i) || linear_.well_posed(i)) return;
      const std::size_t src = inward_well_posed(i, ijk);
      if (src != i) linear_.impose_gradient(grid_, i, linear_.gradient_at_node(grid_, src));
    });
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) { p_node_[i] = linear_.at_node(i); });
    fill_ghosts(p_node_);  // mpirun: the predictor's G p^t reads R columns beyond the rank's
  }

  /// (5b) The role of every node with water: prescribed on the grid faces the water drains
  /// through (p = 0, or the face's value) and on the free surface (free_surface()), with
  /// dp_D = p_D - p^t(x_D); unknown otherwise. Clears the operators for (5a).
  void set_node_roles(const NodeFields<Dim>& water) {
    poisson_.clear(grid_, box_);
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      std::fill_n(D_solid_.data() + i * KD, KD, Vec<Dim>::Zero());
      std::fill_n(D_water_.data() + i * KD, KD, Vec<Dim>::Zero());
    });
    const auto& nn = grid_.nodes_per_axis();
    grid_.for_each_node(box_, [&](std::size_t i, const auto& ijk) {
      if (!(water.acc[i].m > transfer::empty_node_mass)) return;
      // A node on several drained faces (a corner) takes a `pressure` face's value over p = 0,
      // whatever the order of the boundaries; of two `pressure` faces the first in x, y, z order.
      int face = -1;
      for (int a = 0; a < Dim; ++a)
        for (int side = 0; side < 2; ++side) {
          const int f = 2 * a + side;
          if (ijk[a] != (side ? nn[a] - 1 : 0) || !face_drained_[f]) continue;
          if (face < 0 || (face_pressure_[face] == 0.0 && face_pressure_[f] != 0.0)) face = f;
        }
      double p_surface = 0.0;
      const bool surface = face < 0 && free_surface(i, ijk, p_surface);
      if (face >= 0 || surface) {
        const double p_bar = face >= 0 ? face_pressure_[face] : p_surface;
        poisson_.prescribe(i, p_bar - p_node_[i]);
      } else {
        poisson_.set_unknown(i);
      }
    });
  }

  /// (5a) by cell moments: the same weights as add_operators() below, summed per cell as moments
  /// of the points' local coordinates, then each cell's node pairs (exact for shape functions that
  /// are one polynomial per cell; transfer/cell_moments.hpp). B4 6^2: the point-wise scatter took
  /// 1443 instructions per point-step (single-point), 950 per pass (double-point). The points'
  /// moments were added by the P2G passes, soil points first, in schedule order.
  void assemble_from_moments(const StripeSchedule& schedule) {
    if constexpr (kCellMoments) {
      Moments& cm = *moments_;
      const std::size_t nx = static_cast<std::size_t>(grid_.nodes_per_axis()[0]);
      // mpirun: the rows of the shared columns go to the other rank after each colour, as a scatter's.
      auto after_colour = [&](int colour) {
        if (const NodeExchange* x = schedule.exchange()) {
          x->after_colour(colour, poisson_.row(0), node_bytes(laplace_rows()), Reach::support);
          x->after_colour(colour, D_solid_.data(), node_bytes(soil_rows()), Reach::support);
          x->after_colour(colour, D_water_.data(), node_bytes(water_rows()), Reach::support);
        }
      };
      cm.reduce(box_, transfer::stripe_axis(grid_), after_colour, [&](std::size_t first, const typename Moments::CellOperators& op) {
        for (int r = 0; r < NP; ++r) {
          const std::size_t node = first + static_cast<std::size_t>(r / S) * nx + r % S;
          double* lrow = poisson_.row(node) + kRowSlot[r];
          Vec<Dim>* srow = D_solid_.data() + node * KD + kRowSlot[r];
          Vec<Dim>* wrow = D_water_.data() + node * KD + kRowSlot[r];
          for (int k = r; k < NP; ++k) lrow[kColumnSlot[k]] += op.l(r, k);  // lower triangle, as the rows store
          for (int k = 0; k < NP; ++k) {
            srow[kColumnSlot[k]] += op.ds(r, k);
            wrow[kColumnSlot[k]] += op.dw(r, k);
          }
        }
      });
    }
  }

  /// (5a) point by point: fn(p) adds point p's share (add_operators) through the schedule, which
  /// names the operator rows to the ranks' exchange.
  template <class Fn>
  void run_operators(const StripeSchedule& schedule, Fn&& fn) {
    schedule.run(fn, laplace_rows(), soil_rows(), water_rows());
  }
  /// (5a) One point's share of the operators, through the stripe schedule:
  ///   D^s_IK += cs S_I grad S_K,  D^w_IK += cw S_I grad S_K   (eqs. 62-63; cs = (1 - n) V, cw = n V)
  ///   L_IJ += cl grad S_I . grad S_J                            (eq. 61, cl = c V inside the quadrature)
  /// The node pairs are visited once for all three (a phase with c = 0 is skipped at compile time).
  template <bool kSoil, bool kWater>
  void add_operators(const shape::ShapeData<Dim, S>& sd, const Weights& c) {
    std::array<std::size_t, NP> node;
    std::array<double, NP> N;
    std::array<Vec<Dim>, NP> grad;
    int a = 0;
    shape::for_each_node(grid_, sd, [&](std::size_t i, double w, const Vec<Dim>& dN) {
      node[a] = i;
      N[a] = w;
      grad[a] = dN;
      ++a;
    });
    // Row r's pairs. Slots are compile-time (kRowSlot, kColumnSlot); with r a constant too (2D,
    // below) both inner loops unroll completely and every entry is a constant offset from its
    // row's start (B4 6^2: scatter 2433 -> 1588 instructions per point-step, results bitwise equal).
    auto pairs_of_row = [&](int r) __attribute__((always_inline)) {
      double* lrow = poisson_.row(node[r]) + kRowSlot[r];
      const Vec<Dim> g = c.l * grad[r];
      // L is symmetric: only the pairs k >= r (node k at or after node r in flat index: the
      // lower triangle, which the Poisson rows store), 45 of the 81 in 2D.
#pragma GCC unroll 64
      for (int k = r; k < NP; ++k) lrow[kColumnSlot[k]] += g.dot(grad[k]);
      if (N[r] == 0.0) return;
      Vec<Dim>* srow = D_solid_.data() + node[r] * KD + kRowSlot[r];
      Vec<Dim>* wrow = D_water_.data() + node[r] * KD + kRowSlot[r];
      const double sN = c.s * N[r], wN = c.w * N[r];
#pragma GCC unroll 64
      for (int k = 0; k < NP; ++k) {
        if constexpr (kSoil) srow[kColumnSlot[k]] += sN * grad[k];
        if constexpr (kWater) wrow[kColumnSlot[k]] += wN * grad[k];
      }
    };
    if constexpr (NP <= 16) {  // 2D: every row unrolled (3D's 27-64 rows stay a loop: code size)
      [&]<int... R>(std::integer_sequence<int, R...>) { (pairs_of_row(R), ...); }(std::make_integer_sequence<int, NP>{});
    } else {
      for (int r = 0; r < NP; ++r) pairs_of_row(r);
    }
  }

  /// (5c) right-hand side and the CHOLMOD solve; false if L is not positive definite.
  /// kConservative (solver.continuity = conservative, the default): the mixture's volume balance
  /// in conservation form, div[(1 - n) v_s + n v_w] = 0 (the sum of the phases' mass balances with
  /// incompressible constituents), tested with S_I, with the flux interpolated from the nodal
  /// fluxes q_K = (1 - n_K) v_sK + n_K v_wK (n_K of eq. 46):
  ///   rhs_I = -(1/dt) sum_K D0_IK . q_K,   D0_IK = sum_p V_p S_I grad S_K = (D^s + D^w)_IK
  /// (soil points carry (1 - n) V, water points n V: together the mixture volume). Expanded,
  ///   div q = (1 - n) div v_s + n div v_w + (v_w - v_s) . grad n,
  /// the paper's eq. 60 right-hand side -(1/dt)(D^s v_s* + D^w v_w*) (non-conservative) without
  /// the last term. That term is the water leaving a compacting zone; without it B2 consolidates
  /// 15 % too fast (docs/formulations.md, "Continuity in conservation form"). With uniform
  /// porosity both agree. n_of(K) is the nodal porosity.
  template <bool kConservative, class Porosity>
  bool solve(double dt, const NodeFields<Dim>& soil, const NodeFields<Dim>& water, Porosity&& n_of) {
    const double inv_dt = 1.0 / dt;
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto& ijk) {
      if (poisson_.role(i) == Poisson::inactive) return;
      const Vec<Dim>* Ds_i = D_solid_.data() + i * KD;
      const Vec<Dim>* Dw_i = D_water_.data() + i * KD;
      double div = 0.0;
      for (int kk = 0; kk < KD; ++kk) {
        if (!inside(ijk, DSt::offset(kk))) continue;
        const std::size_t Kn = i + d_steps_[kk];
        if constexpr (kConservative) {
          const double nK = n_of(Kn);
          div += (Ds_i[kk] + Dw_i[kk]).dot((1.0 - nK) * soil.v[Kn] + nK * water.v[Kn]);
        } else {
          div += Ds_i[kk].dot(soil.v[Kn]) + Dw_i[kk].dot(water.v[Kn]);
        }
      }
      poisson_.rhs(i) = -inv_dt * div;
    });
    if (domain_) return solve_on_ranks();
    return poisson_.solve(grid_, box_);
  }

  /// f_s -= sum_J G^s_KJ q_J, f_w -= sum_J G^w_KJ q_J at node K: the pressure force of a nodal
  /// field q in the strong form of eqs. 67-68, G^s_KJ = sum_sp (1 - n) V S_K grad S_J = D^s_KJ
  /// (equal-order pressure and velocity shapes: G is D read with the roles of I and J swapped),
  /// i.e. f_s = -sum_sp (1 - n) V S_K grad q(x_sp).
  void add_pressure_force(std::size_t k, const std::array<int, Dim>& ijk, const NodeArray<double>& q, Vec<Dim>& fs,
                          Vec<Dim>& fw) const {
    const Vec<Dim>* Ds_k = D_solid_.data() + k * KD;
    const Vec<Dim>* Dw_k = D_water_.data() + k * KD;
    Vec<Dim> gs = Vec<Dim>::Zero(), gw = Vec<Dim>::Zero();
    for (int kk = 0; kk < KD; ++kk) {
      if (!inside(ijk, DSt::offset(kk))) continue;
      const double qJ = q[k + d_steps_[kk]];
      gs += qJ * Ds_k[kk];
      gw += qJ * Dw_k[kk];
    }
    fs -= gs;
    fw -= gw;
  }

  /// (6)-(7c) p^{t+1} at the points that carry the water: p = (remapped p^t) + sum S dp (Remap).
  /// mass(p): the water mass of point p (the node-remap's weights); a point without water (a dry
  /// single-point point) keeps p = 0. Returns the first point whose pressure is not finite, or -1.
  template <class SD, class Mass>
  long update_points(const StripeSchedule& schedule, const std::vector<SD>& sd, ParticleSet<Dim>& ws, Mass&& mass) {
    if (remap_ == Remap::node)
      constant_.fit(grid_, box_, schedule, sd, ws.x, mass, [&](int p) { return ws.p[p]; });
    // p^{t+1} = remapped p^t at the point + sum S dp, in one visit of its nodes.
    return with_remap([&](auto visit, auto remapped) {
      constexpr bool kRemapped = decltype(remapped)::value;
      const auto& dp = poisson_.dp();
      const long n = static_cast<long>(ws.size());
      long bad = transfer::no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
      for (long p = 0; p < n; ++p) {
        if (!(mass(static_cast<int>(p)) > 0.0)) {
          ws.p[p] = 0.0;
          continue;
        }
        double inc = 0.0, value = 0.0;
        visit(sd[p], ws.x[p], [&](std::size_t i, double N, double pbar) {
          inc += N * dp[i];
          if constexpr (kRemapped) value += N * pbar;
        });
        ws.p[p] = (kRemapped ? value : ws.p[p]) + inc;
        if (!std::isfinite(ws.p[p])) bad = std::min(bad, p);
      }
      return bad == transfer::no_particle ? -1 : bad;
    });
  }

  /// The solver's relative residual |b - L dp| / |b| (CHOLMOD's preconditioned CG; PETSc's KSP).
  static constexpr double kTolerance = Poisson::kTolerance;

  /// Restart: the equations and reused factor of one rank's solver. Under mpirun there are none
  /// (the solves are PETSc's, whose reused preconditioner a resume sets up again): a checkpoint
  /// written there holds none, and a resume on one rank starts CHOLMOD afresh (its answers then agree with the uninterrupted run to the
  /// solver's tolerance); a resume under mpirun ignores a one-rank run's.
  void save(Checkpoint& c) const {
    if (parallel::ranks() == 1) poisson_.save(c, "formulation/poisson");
  }
  void restore(const Checkpoint& c) {
    if (parallel::ranks() == 1 && c.header.contains("formulation/poisson")) poisson_.restore(c, "formulation/poisson");
  }
  /// The solver's work (pressure_poisson.hpp): how often the unknown node set changed (new
  /// pattern and symbolic analysis), numeric factorisations, and CG iterations preconditioned by
  /// an older factor on the other steps.
  template <class Counter>
  std::vector<Counter> counters() const {
    if (domain_)
      return {{"pressure_solves", static_cast<double>(ksp_solves_), "distributed pressure solves (PETSc CG)"},
              {"pressure_ksp_iterations", static_cast<double>(ksp_iterations_), "CG iterations of the distributed solves"},
              {"pressure_preconditioner_setups", static_cast<double>(amg_setups_ + (ranks_poisson_ ? ranks_poisson_->setups() : 0)),
               "BoomerAMG setups (3D) or CHOLMOD factorisations on every rank (2D), each reused by later solves"}};
    return {{"pressure_pattern_builds", static_cast<double>(poisson_.pattern_builds()),
             "new sparsity patterns of L (the set of unknown nodes changed)"},
            {"pressure_factorisations", static_cast<double>(poisson_.factorisations()), "CHOLMOD numeric factorisations"},
            {"pressure_cg_iterations", static_cast<double>(poisson_.cg_iterations()),
             "conjugate-gradient iterations preconditioned by an older factor"}};
  }

 private:
  // Stencil slot of the pair (node r, node k) of one point's support (r, k in for_each_node's
  // order, x fastest), the same in D's and L's stencils (both reach S - 1): the offset is
  // d = k - r per axis, so slot(d) = sum_a (d_a + S - 1) W^a = kRowSlot[r] + kColumnSlot[k].
  static_assert(DSt::W == Poisson::W && DSt::K == Poisson::K);
  static constexpr std::array<int, NP> pair_slot_part(bool row) {
    std::array<int, NP> out{};
    for (int r = 0; r < NP; ++r) {
      int slot = 0, mul = 1, rest = r;
      for (int a = 0; a < Dim; ++a, rest /= S, mul *= DSt::W) slot += (row ? S - 1 - rest % S : rest % S) * mul;
      out[r] = slot;
    }
    return out;
  }
  static constexpr std::array<int, NP> kRowSlot = pair_slot_part(true);
  static constexpr std::array<int, NP> kColumnSlot = pair_slot_part(false);

  /// (5b) Whether node i (with water) is on the free surface (porous::SupportCut's node test),
  /// and its prescribed pressure p_D. With B-splines such a node lies up to about a cell inside or
  /// outside the surface, so p_D = 0 there would move the surface; p_D is instead the value at the
  /// node of the linear fit of the points' pressures shifted to vanish on the surface x_s (the
  /// water's extent along the axis of the largest cut): p_D = -dp/dx_a (x_s - x_Ia). Exact for a
  /// hydrostatic or any linear field (and p_D = 0 for linear/GIMP with a surface through a node row).
  bool free_surface(std::size_t i, const std::array<int, Dim>& ijk, double& p_D) const {
    p_D = 0.0;
    double x_s = 0.0;
    int axis = -1;
    bool hi_cut = false;
    const double cut = surface_.cut(grid_, reach_, i, ijk, axis, hi_cut, x_s);
    if (!surface_.on_surface(cut, grid_)) return false;
    p_D = -linear_.gradient_at_node(grid_, i)[axis] * (x_s - grid_.axis(axis).node_x[ijk[axis]]);
    return true;
  }
  /// The nearest node with a well-posed linear fit from node i inward (towards the water) along
  /// the axis of its largest support cut, within S - 1 steps (the nodes that share points with
  /// i); i itself if there is none (no cut, or a sheet of water thinner than the supports: the
  /// node keeps the Order-0 fit, p_D = 0 at a surface node).
  std::size_t inward_well_posed(std::size_t i, const std::array<int, Dim>& ijk) const {
    int axis = -1;
    bool hi_cut = false;
    double x_s = 0.0;
    surface_.cut(grid_, reach_, i, ijk, axis, hi_cut, x_s);
    if (axis < 0) return i;
    const auto& nn = grid_.nodes_per_axis();
    std::size_t stride = 1;
    for (int a = 0; a < axis; ++a) stride *= static_cast<std::size_t>(nn[a]);
    std::size_t k = i;
    for (int j = ijk[axis], step = 1; step < S; ++step) {
      j += hi_cut ? -1 : 1;
      if (j < 0 || j >= nn[axis]) break;
      k = hi_cut ? k - stride : k + stride;
      if (linear_.well_posed(k)) return k;
    }
    return i;
  }
  /// Whether node ijk + d lies in the nodes this step may read (the box, and under mpirun its ghost
  /// columns; rows outside hold stale values).
  bool inside(const std::array<int, Dim>& ijk, const std::array<int, Dim>& d) const {
    for (int a = 0; a < Dim; ++a)
      if (ijk[a] + d[a] < reach_.lo[a] || ijk[a] + d[a] > reach_.hi[a]) return false;
    return true;
  }
  /// The operator rows as node arrays (K values per node), for the ranks' exchange.
  NodeRows<double> laplace_rows() { return {poisson_.row(0), static_cast<std::size_t>(Poisson::K)}; }
  NodeRows<Vec<Dim>> soil_rows() { return {D_solid_.data(), static_cast<std::size_t>(KD)}; }
  NodeRows<Vec<Dim>> water_rows() { return {D_water_.data(), static_cast<std::size_t>(KD)}; }
  /// (5c) under mpirun: the same system over the ranks (parallel::GridPoisson: PETSc CG with
  /// BoomerAMG to kTolerance), then the increments of the ghost columns. Built again when the cuts
  /// move (a rebalance). False when CG did not converge (an undetermined pressure).
  bool solve_on_ranks() {
    if (!ranks_poisson_ || ranks_cuts_ != domain_->column_cuts()) {
      if (ranks_poisson_) amg_setups_ += ranks_poisson_->setups();
      ranks_cuts_ = domain_->column_cuts();
      ranks_poisson_ = std::make_unique<parallel::GridPoisson<Dim, S - 1>>(grid_, domain_->axis(), ranks_cuts_);
    }
    const auto stats = poisson_.solve_on_ranks(*ranks_poisson_, box_, kTolerance);
    ++ksp_solves_;
    ksp_iterations_ += stats.iterations;
    fill_ghosts(poisson_.dp_nodes());  // the corrections' G dp reads R columns beyond the rank's
    return stats.converged;
  }
  /// Calls body(visit, remapped) with the remap's visitor: visit(sd, x, fn) calls fn(i, N, pbar_I)
  /// at each node of a point (for_each_node's order), pbar_I the nodal term of the remapped p^t at
  /// the point (NodeProjection::for_each_node_value; 0 without remap: remapped is
  /// std::false_type, p^t stays the point's own). One visit gathers the increment too.
  template <class Body>
  auto with_remap(Body&& body) const {
    switch (remap_) {
      case Remap::node:
        return body([&](const auto& sd, const Vec<Dim>& x, auto&& fn)
                        __attribute__((always_inline)) { constant_.for_each_node_value(grid_, sd, x, fn); },
                    std::true_type{});
      case Remap::linear:
        return body([&](const auto& sd, const Vec<Dim>& x, auto&& fn)
                        __attribute__((always_inline)) { linear_.for_each_node_value(grid_, sd, x, fn); },
                    std::true_type{});
      case Remap::none:
        break;
    }
    return body(
        [&](const auto& sd, const Vec<Dim>&, auto&& fn) __attribute__((always_inline)) {
          shape::for_each_node(grid_, sd, [&](std::size_t i, double N, const auto&) { fn(i, N, 0.0); });
        },
        std::false_type{});
  }

  const Grid<Dim>& grid_;
  const NodeBox<Dim>& box_;    // the step's active nodes (the formulation's)
  const NodeBox<Dim>& reach_;  // the nodes whose values the step may read (the box; mpirun: and the ghosts)
  Remap remap_;
  std::array<bool, 6> face_drained_;
  std::array<double, 6> face_pressure_;  // Pa, prescribed p on drained faces (0 unless `pressure`)
  Poisson poisson_;
  porous::SupportCut<Dim, Shape> surface_;
  NodeArray<double> p_node_;               // Pa, per node: p^t from the linear projection of the points' pressures
  NodeArray<Vec<Dim>> D_solid_, D_water_;  // per node: row I of D^s, D^w over the D stencil
  std::unique_ptr<Moments> moments_;         // kCellMoments only
  std::array<long, KD> d_steps_{};
  NodeProjection<Dim, S, 1> linear_;
  NodeProjection<Dim, S, 0> constant_;
  const parallel::Domain<Dim>* domain_ = nullptr;  // mpirun only
  std::unique_ptr<parallel::GridPoisson<Dim, S - 1>> ranks_poisson_;
  std::vector<int> ranks_cuts_;  // the column cuts ranks_poisson_ was built for
  long ksp_solves_ = 0, ksp_iterations_ = 0, amg_setups_ = 0;  // amg_setups_: of the solvers before a re-cut
};

}  // namespace swmpm::semi_implicit
