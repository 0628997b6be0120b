// Time functions, boundary conditions on grid faces, and particle loads (tractions, pressures).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "scene/scene.hpp"
#include "solver/grid/grid.hpp"
#include "solver/particles/particles.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm {

/// f(t) of a scene TimeFunction: ramp(t) * (expression(t) | table(t) | 1).
class TimeFunction {
 public:
  explicit TimeFunction(const scene::TimeFunction& tf);
  ~TimeFunction();
  TimeFunction(TimeFunction&&) noexcept;
  TimeFunction& operator=(TimeFunction&&) noexcept;
  double operator()(double t) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Solid boundary conditions on the grid's faces and on named surfaces, applied to nodal velocities.
template <int Dim>
class GridBoundary {
 public:
  struct Face {
    int axis;  // 0 x, 1 y, 2 z
    int side;  // 0 min, 1 max
    scene::SolidBc kind;
    double mu;  // Coulomb coefficient (friction)
  };
  /// A node under a condition on a named surface: the grid node nearest to one or more of the
  /// surface's samples, with their area-weighted mean outward normal (pointing into the wall).
  struct SurfaceNode {
    std::size_t node;
    Vec<Dim> n;
    scene::SolidBc kind;
    double mu;
  };
  GridBoundary(const scene::Scene& s, const Grid<Dim>& g, const SurfaceSamples<Dim>& samples);
  explicit GridBoundary(std::vector<Face> faces, std::vector<SurfaceNode> nodes = {})
      : faces_(std::move(faces)), nodes_(std::move(nodes)) {}
  /// Conditions on the pore-fluid velocity: an `impermeable` face stops the fluid's normal
  /// velocity (a roller for the fluid); `drained` and `pressure` leave it free (p = 0 is the
  /// natural condition; a prescribed pressure is a load, ParticleLoads). A face without a `fluid`
  /// entry is impermeable where its solid condition is fixed, roller or friction, drained where
  /// it is free; grid faces not listed at all are drained.
  static GridBoundary fluid(const scene::Scene& s, const Grid<Dim>& g, const SurfaceSamples<Dim>& samples);
  /// Enforces the conditions on v for nodes of `box` that lie on a constrained face, and on the
  /// nodes of named surfaces. Friction acts only when `with_friction` (on the end-of-step
  /// velocity; the start-of-step velocity only gets the kinematic constraints).
  void apply(const Grid<Dim>& g, const NodeBox<Dim>& box, NodeArray<Vec<Dim>>& v, bool with_friction) const;
  const std::vector<Face>& faces() const { return faces_; }
  const std::vector<SurfaceNode>& surface_nodes() const { return nodes_; }

 private:
  std::vector<Face> faces_;
  std::vector<SurfaceNode> nodes_;
};

/// Tractions and pressures on bodies' faces, as forces on the face particles; and prescribed pore
/// pressures (`boundaries[].fluid: "pressure"`), as the same kind of force shared between the
/// phases by porosity (`split`), for formulations whose pore-pressure force is the weak form
/// (integrated by parts, so the boundary term is a load). A formulation with the strong gradient
/// -grad p (semi-implicit: the prescribed p is a Dirichlet value of its pressure equation, and the
/// strong form already holds the boundary term) passes pore_pressure_forces = false.
template <int Dim>
class ParticleLoads {
 public:
  ParticleLoads(const scene::Scene& s, const Grid<Dim>& g, const ParticleSet<Dim>& ps,
                const SurfaceSamples<Dim>& samples, bool pore_pressure_forces = true);
  /// Calls fn(p, f_p(t), face offset, split) for every loaded particle (serial; few particles).
  /// The force acts on the body's surface, at x_p + offset (the particle domain's face point, or
  /// the centroid of the named surface's share), so formulations evaluate the shape functions
  /// there rather than at the particle centre: a traction then loads the nodes of the surface,
  /// not those around the first particle row. `split`: a prescribed pore pressure p on the
  /// mixture's surface, f = -p A n; the solid takes (1 - n_p) f and the fluid n_p f (the boundary
  /// terms of sigma_s = sigma' - (1 - n) p I and sigma_f = -n p I). `index_of_id` maps particle
  /// ids to current indices (State::index_of_id).
  template <class Fn>
  void for_each_force(double t, const std::vector<int>& index_of_id, Fn&& fn) const {
    for_each_numbered_force(t, index_of_id, [&](std::int64_t, int p, const Vec<Dim>& f, const Vec<Dim>& offset,
                                                bool split) { fn(p, f, offset, split); });
  }
  /// for_each_force with each force's place in the list of all loaded particles (every load's,
  /// in order), fn(ordinal, p, f, offset, split): the order in which one rank adds them.
  template <class Fn>
  void for_each_numbered_force(double t, const std::vector<int>& index_of_id, Fn&& fn) const {
    std::int64_t ordinal = 0;
    for (const auto& e : entries_) {
      const double scale = e.fn(t);
      if (scale == 0.0) {
        ordinal += static_cast<std::int64_t>(e.ids.size());
        continue;
      }
      for (std::size_t k = 0; k < e.ids.size(); ++k, ++ordinal)
        if (const int p = index_of_id[e.ids[k]]; p >= 0)  // -1: held by another rank (mpirun)
          fn(ordinal, p, (scale * e.force[k]).eval(), e.offset[k], e.split);
    }
  }
  std::size_t count() const { return entries_.size(); }
  /// Number of particles a load acts on (to report and test the tagging); loads come first, in
  /// scene order, then prescribed pore pressures in the order of `boundaries`.
  std::size_t particles(std::size_t load) const { return entries_[load].ids.size(); }
  /// The largest stress the loads apply at time t (Pa): |traction|, |pressure| or a prescribed
  /// pore pressure's |p|, times |f(t)|; 0 without loads. The scale of physical-bounds checks.
  double stress_scale(double t) const {
    double s = 0.0;
    for (const auto& e : entries_) s = std::max(s, e.stress * std::abs(e.fn(t)));
    return s;
  }
  /// Sum of the load's forces at f(t) = 1 (N, or N/m in 2D).
  Vec<Dim> resultant(std::size_t load) const {
    Vec<Dim> r = Vec<Dim>::Zero();
    for (const auto& f : entries_[load].force) r += f;
    return r;
  }

 private:
  struct Entry {
    std::vector<std::int64_t> ids;  // particle ids (stable under reordering)
    std::vector<Vec<Dim>> force;   // N (N/m in 2D) at f(t) = 1
    std::vector<Vec<Dim>> offset;  // m, from the particle centre to its point of action
    TimeFunction fn;
    bool split = false;  // a prescribed pore pressure: shared between the phases by porosity
    double stress = 0.0;  // Pa at f(t) = 1: |traction|, |pressure| or |prescribed pore pressure|
  };
  std::vector<Entry> entries_;
};

/// A load's force with the shape data at its point of action (ParticleLoads::for_each_force).
template <int Dim, int S>
struct FaceForce {
  shape::ShapeData<Dim, S> sd;  // shape functions at the face point
  Vec<Dim> f;                   // N (N/m in 2D)
  int p;                        // particle index (-1: a particle another rank holds, mpirun)
  bool split;                   // shared between solid and fluid by porosity (ParticleLoads)
  double n = 0.0;               // the particle's porosity (two-phase sets), for `split`
  Vec<Dim> x = Vec<Dim>::Zero();  // m, the face point
  std::int64_t ordinal = 0;     // its place in the list of all loaded particles (for_each_numbered_force)
  double scale = 0.0;           // 1 / sum of N over its nodes that carry mass (weigh_face_forces)
};

/// The loads' forces at time t with their shape data, and the active node box grown to hold them
/// (a face point can reach a node no particle centre touches). Shared by every formulation.
template <class Shape, int Dim>
void collect_face_forces(const Grid<Dim>& g, const ParticleLoads<Dim>& loads, const ParticleSet<Dim>& ps,
                         const std::vector<int>& index_of_id, double t, NodeBox<Dim>& box,
                         std::vector<FaceForce<Dim, Shape::support>>& out) {
  out.clear();
  loads.for_each_numbered_force(t, index_of_id, [&](std::int64_t ordinal, int p, const Vec<Dim>& f_p,
                                                    const Vec<Dim>& offset, bool split) {
    FaceForce<Dim, Shape::support> ff{{}, f_p, p, split};
    ff.n = ps.n.empty() ? 0.0 : ps.n[p];
    ff.x = (ps.x[p] + offset).cwiseMax(g.min()).cwiseMin(g.max());
    ff.ordinal = ordinal;
    shape::evaluate<Shape>(g, ff.x, Vec<Dim>::Zero().eval(), ff.sd);
    for (int a = 0; a < Dim; ++a) {
      box.lo[a] = std::min(box.lo[a], ff.sd.base[a]);
      box.hi[a] = std::max(box.hi[a], ff.sd.base[a] + Shape::support - 1);
    }
    out.push_back(ff);
  });
}

/// Distributes one face force over the nodes of its face point that carry mass: fn(node, weight)
/// with weight = N_I(x_face) / sum of N_J(x_face) over the nodes J with has_mass(J). A node
/// without mass gets no velocity in the grid update, so a share given to it would be lost: with
/// linear shape functions a particle sitting on a node leaves the next node up massless while its
/// face point still weighs it 1/2 (A2 on linear, h = 0.025 m, lost half its top load). The force
/// and its resultant are kept exactly; only where it acts moves to the loaded nodes.
/// The weights of the nodes take the sum in weigh_face_forces (called once the masses are
/// scattered), so that under mpirun the rank that holds all of a face point's nodes can weigh it
/// for every rank (parallel::weigh_face_forces).
template <int Dim, int S, class HasMass>
double face_force_scale(const Grid<Dim>& g, const FaceForce<Dim, S>& ff, HasMass&& has_mass) {
  double total = 0.0;
  shape::for_each_node(g, ff.sd, [&](std::size_t i, double N, const Vec<Dim>&) {
    if (has_mass(i)) total += N;
  });
  return total > 0.0 ? 1.0 / total : 0.0;  // 0: no loaded node at all (the particle's own nodes hold its mass, so not reached)
}
template <int Dim, int S, class HasMass>
void weigh_face_forces(const Grid<Dim>& g, std::vector<FaceForce<Dim, S>>& ffs, HasMass&& has_mass) {
  for (auto& ff : ffs) ff.scale = face_force_scale(g, ff, has_mass);
}
template <int Dim, int S, class HasMass, class Fn>
void for_each_loaded_node(const Grid<Dim>& g, const FaceForce<Dim, S>& ff, HasMass&& has_mass, Fn&& fn) {
  if (!(ff.scale > 0.0)) return;
  shape::for_each_node(g, ff.sd, [&](std::size_t i, double N, const Vec<Dim>&) {
    if (has_mass(i)) fn(i, N * ff.scale);
  });
}

/// The nodes of `nodes` that carry mass (transfer::empty_node_mass), as for_each_loaded_node
/// reads them.
template <int Dim>
auto carries_mass(const NodeFields<Dim>& nodes) {
  return [&nodes](std::size_t i) { return nodes.acc[i].m > transfer::empty_node_mass; };
}
/// The face forces, once weighed (weigh_face_forces), added to the nodal forces of `nodes` in the
/// loads' order (after the scatter of the masses).
template <int Dim, int S>
void add_weighed_face_forces(const Grid<Dim>& g, const std::vector<FaceForce<Dim, S>>& ffs, NodeFields<Dim>& nodes) {
  for (const auto& ff : ffs)
    for_each_loaded_node(g, ff, carries_mass(nodes), [&](std::size_t i, double N) { nodes.acc[i].f += N * ff.f; });
}
/// weigh_face_forces on the masses of `nodes`, then add_weighed_face_forces (one rank).
template <int Dim, int S>
void add_face_forces(const Grid<Dim>& g, std::vector<FaceForce<Dim, S>>& ffs, NodeFields<Dim>& nodes) {
  weigh_face_forces(g, ffs, carries_mass(nodes));
  add_weighed_face_forces(g, ffs, nodes);
}

/// Face index 2 * axis + side of a face name x_min .. z_max.
int face_index(const std::string& name);

/// Whether a particle domain [x - l, x + l] ends on grid face f (face_index's numbering), to
/// within half its half-size: the particles a prescribed pore pressure on that face reaches.
template <int Dim>
bool domain_ends_on_face(const Grid<Dim>& g, int f, const Vec<Dim>& x, const Vec<Dim>& l) {
  const int axis = f / 2;
  const double outward = f % 2 == 0 ? -1.0 : 1.0;
  const double plane = f % 2 == 0 ? g.min()[axis] : g.max()[axis];
  return std::abs(x[axis] + outward * l[axis] - plane) <= 0.5 * l[axis];
}

}  // namespace swmpm
