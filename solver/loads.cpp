#include "solver/loads.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <stdexcept>
#include <unordered_map>

#include <muParser.h>

#include "scene/expression.hpp"
#include "scene/input.hpp"
#include "solver/parallel/domain.hpp"

namespace swmpm {

struct TimeFunction::Impl {
  double ramp = 0.0;
  std::vector<std::array<double, 2>> table;
  std::unique_ptr<mu::Parser> parser;
  std::string expression;
  mutable double t = 0.0;  // the parser's variable
};

TimeFunction::TimeFunction(const scene::TimeFunction& tf) : impl_(std::make_unique<Impl>()) {
  impl_->ramp = tf.ramp;
  impl_->table = tf.table;
  if (!tf.expression.empty()) {
    impl_->parser = std::make_unique<mu::Parser>();
    impl_->parser->DefineVar("t", &impl_->t);
    impl_->parser->DefineConst("pi", M_PI);
    impl_->parser->SetExpr(tf.expression);
    impl_->expression = tf.expression;
  }
}
TimeFunction::~TimeFunction() = default;
TimeFunction::TimeFunction(TimeFunction&&) noexcept = default;
TimeFunction& TimeFunction::operator=(TimeFunction&&) noexcept = default;

double TimeFunction::operator()(double t) const {
  double f = 1.0;
  if (impl_->parser) {
    impl_->t = t;
    f = impl_->parser->Eval();
    // The scene check evaluated it at nine times; a value that is not finite between them stops
    // the run here, naming the expression, rather than as a divergence blamed on the material.
    if (!std::isfinite(f)) {
      char at[64];
      std::snprintf(at, sizeof at, "%.10g", t);
      throw scene::ExpressionValueError(impl_->expression, "got \"" + scene::shortened(impl_->expression) +
                                                               "\", which is " + (std::isnan(f) ? "nan" : f > 0 ? "inf" : "-inf") +
                                                               " at t = " + at + " s; expected a finite value");
    }
  } else if (!impl_->table.empty()) {
    const auto& tab = impl_->table;
    if (t <= tab.front()[0]) f = tab.front()[1];
    else if (t >= tab.back()[0]) f = tab.back()[1];
    else {
      auto it = std::upper_bound(tab.begin(), tab.end(), t, [](double v, const auto& row) { return v < row[0]; });
      const auto& b = *it;
      const auto& a = *(it - 1);
      f = a[1] + (b[1] - a[1]) * (t - a[0]) / (b[0] - a[0]);
    }
  }
  if (impl_->ramp > 0.0) f *= std::min(1.0, t / impl_->ramp);
  return f;
}

int face_index(const std::string& name) {
  const int f = scene::grid_face_index(name);
  if (f < 0) throw std::runtime_error("unknown face \"" + name + "\"");
  return f;
}

namespace {

bool is_axis_face(const std::string& name) { return scene::grid_face_index(name) >= 0; }

/// k of the named surface `name` (face bit kFirstSurfaceBit + k); `what` names the JSON place.
int surface_index(const scene::Scene& s, const std::string& name, const std::string& what) {
  const auto names = scene::surface_bit_names(s);
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) throw std::runtime_error(what + ": unknown surface \"" + name + "\"");
  return static_cast<int>(it - names.begin());
}

/// The grid nodes a condition on surface k constrains: those within half a cell of the surface
/// and those behind it (outside the body) within the shape functions' reach, so the surface acts
/// as a rigid wall: a particle whose domain slides past the surface meets constrained nodes only
/// (an unconstrained node behind the surface would take its mass and let it sink through). Each
/// node takes the outward normal of its nearest sample. In node order (deterministic).
template <int Dim>
std::vector<typename GridBoundary<Dim>::SurfaceNode> nodes_of_surface(const scene::Scene& s, const Grid<Dim>& g,
                                                                      const SurfaceSamples<Dim>& smp, int k,
                                                                      scene::SolidBc kind, double mu) {
  const double h = g.h();
  double reach = 1.5 * h;  // GIMP (h + l <= 1.5 h) and quadratic B-splines
  if (s.grid.shape_function == scene::ShapeFunction::linear) reach = h;
  if (s.grid.shape_function == scene::ShapeFunction::bspline3) reach = 2.0 * h;
  std::map<std::size_t, std::pair<double, Vec<Dim>>> best;  // node -> (distance to the nearest sample, its normal)
  for (std::size_t j = 0; j < smp.size(); ++j) {
    if (smp.surface[j] != k) continue;
    const Vec<Dim>& xs = smp.x[j];
    const Vec<Dim>& n = smp.normal[j];
    NodeBox<Dim> box;
    const auto lo = g.nearest_node((xs.array() - reach - h).matrix().eval());
    const auto hi = g.nearest_node((xs.array() + reach + h).matrix().eval());
    box.lo = lo;
    box.hi = hi;
    g.for_each_node(box, [&](std::size_t node, const std::array<int, Dim>& ijk) {
      const Vec<Dim> d = g.node_position(ijk) - xs;
      const double along = d.dot(n);                    // > 0: behind the surface (outside the body)
      const double across = (d - along * n).norm();      // tangential distance
      if (along < -0.5 * h || along > reach || across > 0.5 * h) return;
      const double dist = d.norm();
      auto [it, fresh] = best.try_emplace(node, dist, n);
      if (!fresh && dist < it->second.first) it->second = {dist, n};
    });
  }
  std::vector<typename GridBoundary<Dim>::SurfaceNode> out;
  for (const auto& [node, dn] : best) out.push_back({node, dn.second, kind, mu});
  return out;
}

/// One velocity constraint: v is the node's velocity, n the outward normal of the body (into the
/// wall), e.g. -e_x on an x_min face.
template <int Dim>
void constrain(Vec<Dim>& v, const Vec<Dim>& n, scene::SolidBc kind, double mu, bool with_friction) {
  switch (kind) {
    case scene::SolidBc::fixed: v.setZero(); break;
    case scene::SolidBc::roller: v -= v.dot(n) * n; break;
    case scene::SolidBc::friction: {
      const double vn = v.dot(n);  // > 0: moving into the wall
      if (vn <= 0.0) break;
      v -= vn * n;
      if (!with_friction) break;
      // Coulomb friction (Bardenhagen et al. 2001): the tangential speed drops by mu * vn.
      const double vt = v.norm();
      if (vt > 0.0) v *= std::max(0.0, 1.0 - mu * vn / vt);
      break;
    }
    case scene::SolidBc::free: break;
  }
}

}  // namespace

template <int Dim>
GridBoundary<Dim>::GridBoundary(const scene::Scene& s, const Grid<Dim>& g, const SurfaceSamples<Dim>& samples) {
  for (std::size_t i = 0; i < s.boundaries.size(); ++i) {
    const auto& b = s.boundaries[i];
    if (b.solid == scene::SolidBc::free) continue;
    if (is_axis_face(b.on)) {
      const int f = face_index(b.on);
      faces_.push_back({f / 2, f % 2, b.solid, b.coefficient});
      continue;
    }
    const int k = surface_index(s, b.on, "boundaries/" + std::to_string(i) + "/on");
    const auto nodes = nodes_of_surface(s, g, samples, k, b.solid, b.coefficient);
    if (nodes.empty())
      throw std::runtime_error("boundaries/" + std::to_string(i) + "/on: the named surface \"" + b.on +
                               "\" has no samples in particles/surfaces.vtu (run swmpm preprocess again)");
    nodes_.insert(nodes_.end(), nodes.begin(), nodes.end());
  }
}

template <int Dim>
GridBoundary<Dim> GridBoundary<Dim>::fluid(const scene::Scene& s, const Grid<Dim>& g,
                                           const SurfaceSamples<Dim>& samples) {
  std::vector<Face> faces;
  std::vector<SurfaceNode> nodes;
  for (std::size_t i = 0; i < s.boundaries.size(); ++i) {
    const auto& b = s.boundaries[i];
    const bool impermeable = b.fluid ? *b.fluid == scene::FluidBc::impermeable : b.solid != scene::SolidBc::free;
    if (!impermeable) continue;
    if (is_axis_face(b.on)) {
      const int f = face_index(b.on);
      faces.push_back({f / 2, f % 2, scene::SolidBc::roller, 0.0});
      continue;
    }
    const int k = surface_index(s, b.on, "boundaries/" + std::to_string(i) + "/on");
    const auto more = nodes_of_surface(s, g, samples, k, scene::SolidBc::roller, 0.0);
    nodes.insert(nodes.end(), more.begin(), more.end());
  }
  return GridBoundary(std::move(faces), std::move(nodes));
}

template <int Dim>
void GridBoundary<Dim>::apply(const Grid<Dim>& g, const NodeBox<Dim>& box, NodeArray<Vec<Dim>>& v,
                              bool with_friction) const {
  for (const Face& face : faces_) {
    const int i_face = face.side == 0 ? 0 : g.nodes_per_axis()[face.axis] - 1;
    if (i_face < box.lo[face.axis] || i_face > box.hi[face.axis]) continue;
    NodeBox<Dim> fb = box;
    fb.lo[face.axis] = fb.hi[face.axis] = i_face;
    Vec<Dim> n = Vec<Dim>::Zero();
    n[face.axis] = face.side == 0 ? -1.0 : 1.0;  // outward normal of the grid face
    g.for_each_node(fb, [&](std::size_t i, const auto&) { constrain<Dim>(v[i], n, face.kind, face.mu, with_friction); });
  }
  // Nodes outside the active box hold stale velocities no particle reads; constraining them is harmless.
  for (const SurfaceNode& sn : nodes_) constrain<Dim>(v[sn.node], sn.n, sn.kind, sn.mu, with_friction);
}

namespace {

/// Shares the samples of surface k on body `body` (inside `region`, when given) among the
/// particles `cand`: each sample goes to the nearest candidate within 1.5 lattice spacings. Per
/// candidate: the length/area it receives, the area-weighted sum of normals, and of the offsets
/// from the particle centre to the samples. A surface at any angle then carries its exact length
/// or area, however the lattice aliases the band of tagged particles.
template <int Dim>
void share_samples(const ParticleSet<Dim>& ps, const std::vector<int>& cand, const SurfaceSamples<Dim>& smp, int k,
                   int body, const std::optional<std::pair<scene::Vec3, scene::Vec3>>& region, std::vector<double>& area,
                   std::vector<Vec<Dim>>& normal, std::vector<Vec<Dim>>& offset) {
  area.assign(cand.size(), 0.0);
  normal.assign(cand.size(), Vec<Dim>::Zero());
  offset.assign(cand.size(), Vec<Dim>::Zero());
  if (cand.empty()) return;
  double reach = 0.0;
  for (int p : cand) reach = std::max(reach, 3.0 * ps.l[p].maxCoeff());  // 1.5 spacings
  // Buckets of size `reach`: a sample's nearest candidate within reach is in its 3^Dim neighbourhood.
  auto key = [&](const Vec<Dim>& x, const std::array<long, Dim>& shift) {
    std::int64_t h = 0;
    for (int a = 0; a < Dim; ++a) h = h * 2000003 + static_cast<std::int64_t>(std::floor(x[a] / reach)) + shift[a];
    return h;
  };
  std::unordered_map<std::int64_t, std::vector<int>> buckets;
  std::array<long, Dim> zero{};
  for (std::size_t c = 0; c < cand.size(); ++c) buckets[key(ps.x0[cand[c]], zero)].push_back(static_cast<int>(c));
  for (std::size_t j = 0; j < smp.size(); ++j) {
    if (smp.surface[j] != k || smp.body[j] != body) continue;
    if (region) {
      bool in = true;
      for (int a = 0; a < Dim; ++a) in = in && smp.x[j][a] >= region->first[a] && smp.x[j][a] <= region->second[a];
      if (!in) continue;
    }
    int best = -1;
    double best_d = reach;
    std::array<long, Dim> shift{};
    for (int n = 0; n < (Dim == 2 ? 9 : 27); ++n) {
      for (int a = 0, r = n; a < Dim; ++a, r /= 3) shift[a] = r % 3 - 1;
      const auto it = buckets.find(key(smp.x[j], shift));
      if (it == buckets.end()) continue;
      for (int c : it->second) {
        const double d = (ps.x0[cand[c]] - smp.x[j]).norm();
        if (d < best_d || (d == best_d && best >= 0 && c < best)) {
          best_d = d;
          best = c;
        }
      }
    }
    if (best < 0) continue;  // the surface reaches past the body (or the region)
    area[best] += smp.area[j];
    normal[best] += smp.area[j] * smp.normal[j];
    offset[best] += smp.area[j] * (smp.x[j] - ps.x0[cand[best]]);
  }
}

}  // namespace

namespace {

/// The face bits (ParticleSet::faces) of the faces and named surfaces the scene loads: the
/// particles the loads are built from carry one of them.
std::uint32_t loaded_faces(const scene::Scene& s, bool pore_pressure_forces) {
  std::uint32_t mask = 0;
  auto add = [&](const std::string& face, const std::string& where) {
    mask |= 1u << (is_axis_face(face) ? face_index(face) : scene::kFirstSurfaceBit + surface_index(s, face, where));
  };
  for (std::size_t i = 0; i < s.loads.size(); ++i) add(s.loads[i].face, "loads/" + std::to_string(i) + "/face");
  for (std::size_t i = 0; pore_pressure_forces && i < s.boundaries.size(); ++i) {
    const auto& b = s.boundaries[i];
    if (b.fluid && *b.fluid == scene::FluidBc::pressure) add(b.on, "boundaries/" + std::to_string(i) + "/on");
  }
  return mask;
}

/// Under mpirun the loads are built while each rank holds a slice of the particles (a fresh
/// start, State::shares): every rank's particles on a loaded face, gathered on every rank in the
/// one-rank order (keys), so that every rank builds the one-rank lists. Collective.
template <int Dim>
ParticleSet<Dim> loaded_particles_over_ranks(const ParticleSet<Dim>& ps, std::uint32_t mask) {
  ParticleSet<Dim> mine = ps.empty_like();
  mine.for_each_field_with(ps, [&](auto& to, const auto& from) {
    if (from.size() != ps.size()) return;  // a field the set does not carry
    for (std::size_t p = 0; p < ps.size(); ++p)
      if (ps.faces[p] & mask) to.push_back(from[p]);
  });
  return parallel::all_gather_set(mine);
}

}  // namespace

template <int Dim>
ParticleLoads<Dim>::ParticleLoads(const scene::Scene& s, const Grid<Dim>& g, const ParticleSet<Dim>& local,
                                  const SurfaceSamples<Dim>& samples, bool pore_pressure_forces) {
  const std::uint32_t mask = loaded_faces(s, pore_pressure_forces);
  ParticleSet<Dim> gathered;
  if (parallel::distributed() && mask) gathered = loaded_particles_over_ranks(local, mask);
  const ParticleSet<Dim>& ps = parallel::distributed() ? gathered : local;
  auto body_index = [&](const std::string& name) {
    for (std::size_t b = 0; b < s.bodies.size(); ++b)
      if (s.bodies[b].name == name) return static_cast<int>(b);
    return -1;
  };
  auto in_region = [&](std::size_t p, const std::optional<std::pair<scene::Vec3, scene::Vec3>>& region) {
    if (!region) return true;
    for (int a = 0; a < Dim; ++a)
      if (ps.x0[p][a] < region->first[a] || ps.x0[p][a] > region->second[a]) return false;
    return true;
  };
  // Axis face f = 2 axis + side: particle p's face point (x_p + l_p along the outward normal) with
  // its nominal face area A_p (the domain's extent across the face; unit thickness in 2D), loaded
  // by the traction t A_p (`traction` given) or by the normal stress sn A_p n (sn = -pressure).
  auto add_axis_face = [&](Entry& e, std::size_t p, int f, double sn, const scene::Vec3* traction) {
    const int axis = f / 2;
    const double outward = f % 2 == 0 ? -1.0 : 1.0;
    double area = 1.0;
    for (int a = 0; a < Dim; ++a)
      if (a != axis) area *= 2.0 * ps.l[p][a];
    Vec<Dim> force = Vec<Dim>::Zero(), offset = Vec<Dim>::Zero();
    if (traction)
      for (int a = 0; a < Dim; ++a) force[a] = (*traction)[a] * area;
    else
      force[axis] = outward * sn * area;
    offset[axis] = outward * ps.l[p][axis];
    e.ids.push_back(ps.id[p]);
    e.force.push_back(force);
    e.offset.push_back(offset);
  };
  // Named surface k: the tagged particles of `keep` share the surface's samples (share_samples);
  // force_of(area, area-weighted normal) is each one's force at f(t) = 1.
  auto add_named = [&](Entry& e, int k, int body, const std::optional<std::pair<scene::Vec3, scene::Vec3>>& region,
                       auto&& keep, auto&& force_of) {
    std::vector<int> cand;
    for (std::size_t p = 0; p < ps.size(); ++p)
      if ((ps.faces[p] & (1u << (scene::kFirstSurfaceBit + k))) && keep(p) && in_region(p, region))
        cand.push_back(static_cast<int>(p));
    std::vector<double> area;
    std::vector<Vec<Dim>> normal, offset;
    for (int b = 0; b < static_cast<int>(s.bodies.size()); ++b) {
      if (body >= 0 && b != body) continue;
      std::vector<int> of_body;
      for (int p : cand)
        if (ps.body[p] == b) of_body.push_back(p);
      share_samples(ps, of_body, samples, k, b, region, area, normal, offset);
      for (std::size_t c = 0; c < of_body.size(); ++c) {
        if (!(area[c] > 0.0)) continue;
        e.ids.push_back(ps.id[of_body[c]]);
        e.force.push_back(force_of(area[c], normal[c]));
        e.offset.push_back(offset[c] / area[c]);
      }
    }
  };

  for (std::size_t i = 0; i < s.loads.size(); ++i) {
    const auto& load = s.loads[i];
    const int body = body_index(load.body);
    Entry e{{}, {}, {}, TimeFunction(load.function), false, 0.0};
    for (int a = 0; a < (load.type == "pressure" ? 1 : Dim); ++a) e.stress += load.value[a] * load.value[a];
    e.stress = std::sqrt(e.stress);
    if (!is_axis_face(load.face)) {
      // A named surface: the particles preprocess tagged within one lattice spacing of it share
      // its samples, so the load carries the surface's exact length or area at any angle.
      const int k = surface_index(s, load.face, "loads/" + std::to_string(i) + "/face");
      const bool pressure = load.type == "pressure";
      Vec<Dim> tr;
      for (int a = 0; a < Dim; ++a) tr[a] = load.value[a];
      add_named(e, k, body, load.region, [&](std::size_t p) { return ps.body[p] == body; },
                [&](double area, const Vec<Dim>& an) -> Vec<Dim> {
                  return pressure ? Vec<Dim>(-load.value[0] * an) : Vec<Dim>(area * tr);  // a pressure pushes inward
                });
      entries_.push_back(std::move(e));
      continue;
    }
    // An axis face (x_min ... z_max): the body's surface layer facing that way, loaded at the
    // particles' face points with their nominal face area (exact: the layer follows the lattice).
    const int f = face_index(load.face);
    for (std::size_t p = 0; p < ps.size(); ++p) {
      if (ps.body[p] != body || !(ps.faces[p] & (1u << f)) || !in_region(p, load.region)) continue;
      if (load.type == "pressure") add_axis_face(e, p, f, -load.value[0], nullptr);  // pushes inward
      else add_axis_face(e, p, f, 0.0, &load.value);
    }
    entries_.push_back(std::move(e));
  }

  // Prescribed pore pressure p on a boundary: -p A n on the saturated particles at it, split
  // between the phases by porosity when applied (for_each_force's `split`).
  for (std::size_t i = 0; pore_pressure_forces && i < s.boundaries.size(); ++i) {
    const auto& b = s.boundaries[i];
    if (!b.fluid || *b.fluid != scene::FluidBc::pressure) continue;
    const std::string where = "boundaries/" + std::to_string(i) + "/fluid";
    if (!ps.two_phase())
      throw std::runtime_error(where + ": a prescribed pore pressure needs pore fluid on the particles; this "
                               "formulation's particles carry none");
    Entry e{{}, {}, {}, TimeFunction(scene::TimeFunction{}), true, std::abs(b.fluid_value)};
    auto wet = [&](std::size_t p) { return ps.fluid_material[p] >= 0; };
    if (!is_axis_face(b.on)) {
      const int k = surface_index(s, b.on, "boundaries/" + std::to_string(i) + "/on");
      add_named(e, k, -1, std::nullopt, wet, [&](double, const Vec<Dim>& an) -> Vec<Dim> { return -b.fluid_value * an; });
    } else {
      // The saturated particles whose face point lies on the grid face.
      const int f = face_index(b.on);
      for (std::size_t p = 0; p < ps.size(); ++p)
        if (wet(p) && (ps.faces[p] & (1u << f)) && domain_ends_on_face(g, f, ps.x0[p], ps.l[p]))
          add_axis_face(e, p, f, -b.fluid_value, nullptr);
    }
    if (e.ids.empty())
      throw std::runtime_error(where + ": no saturated particle lies on \"" + b.on +
                               "\", so the prescribed pore pressure would act on nothing");
    entries_.push_back(std::move(e));
  }
}

template class GridBoundary<2>;
template class GridBoundary<3>;
template class ParticleLoads<2>;
template class ParticleLoads<3>;

}  // namespace swmpm
