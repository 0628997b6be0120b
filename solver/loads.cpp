#include "solver/loads.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <muParser.h>

namespace swmpm {

struct TimeFunction::Impl {
  double ramp = 0.0;
  std::vector<std::array<double, 2>> table;
  std::unique_ptr<mu::Parser> parser;
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
  static const char* names[] = {"x_min", "x_max", "y_min", "y_max", "z_min", "z_max"};
  for (int f = 0; f < 6; ++f)
    if (name == names[f]) return f;
  throw std::runtime_error("unknown face \"" + name + "\"");
}

namespace {
bool is_axis_face(const std::string& name) {
  return name.size() == 5 && (name[0] == 'x' || name[0] == 'y' || name[0] == 'z') &&
         (name.substr(1) == "_min" || name.substr(1) == "_max");
}
}  // namespace

template <int Dim>
GridBoundary<Dim>::GridBoundary(const scene::Scene& s) {
  for (const auto& b : s.boundaries) {
    if (!is_axis_face(b.on))
      throw std::runtime_error("boundaries: \"" + b.on + "\" is a named surface; the solver applies boundary "
                               "conditions on grid faces (x_min ... z_max) only in this version");
    const int f = face_index(b.on);
    if (b.solid == scene::SolidBc::free) continue;
    faces_.push_back({f / 2, f % 2, b.solid, b.coefficient});
  }
}

template <int Dim>
GridBoundary<Dim> GridBoundary<Dim>::fluid(const scene::Scene& s) {
  std::vector<Face> faces;
  for (const auto& b : s.boundaries) {
    if (!is_axis_face(b.on)) continue;  // rejected with a message by the solid GridBoundary
    const int f = face_index(b.on);
    const bool impermeable = b.fluid ? *b.fluid == scene::FluidBc::impermeable : b.solid != scene::SolidBc::free;
    if (b.fluid && *b.fluid == scene::FluidBc::pressure)
      throw std::runtime_error("boundaries: fluid \"pressure\" on " + b.on + " is not implemented yet in this version");
    if (impermeable) faces.push_back({f / 2, f % 2, scene::SolidBc::roller, 0.0});
  }
  return GridBoundary(std::move(faces));
}

template <int Dim>
void GridBoundary<Dim>::apply(const Grid<Dim>& g, const NodeBox<Dim>& box, std::vector<Vec<Dim>>& v,
                              bool with_friction) const {
  for (const Face& face : faces_) {
    const int i_face = face.side == 0 ? 0 : g.nodes_per_axis()[face.axis] - 1;
    if (i_face < box.lo[face.axis] || i_face > box.hi[face.axis]) continue;
    NodeBox<Dim> fb = box;
    fb.lo[face.axis] = fb.hi[face.axis] = i_face;
    const double n = face.side == 0 ? -1.0 : 1.0;  // outward normal component along the axis
    g.for_each_node(fb, [&](std::size_t i, const auto&) {
      Vec<Dim>& vi = v[i];
      switch (face.kind) {
        case scene::SolidBc::fixed: vi.setZero(); break;
        case scene::SolidBc::roller: vi[face.axis] = 0.0; break;
        case scene::SolidBc::friction: {
          const double vn = vi[face.axis] * n;  // > 0: moving into the wall
          if (vn <= 0.0) break;
          vi[face.axis] = 0.0;
          if (!with_friction) break;
          // Coulomb friction (Bardenhagen et al. 2001): the tangential speed drops by mu * vn.
          const double vt = vi.norm();
          if (vt > 0.0) vi *= std::max(0.0, 1.0 - face.mu * vn / vt);
          break;
        }
        case scene::SolidBc::free: break;
      }
    });
  }
}

template <int Dim>
ParticleLoads<Dim>::ParticleLoads(const scene::Scene& s, const ParticleSet<Dim>& ps) {
  for (const auto& load : s.loads) {
    int body = -1;
    for (std::size_t b = 0; b < s.bodies.size(); ++b)
      if (s.bodies[b].name == load.body) body = static_cast<int>(b);
    // An axis face (x_min ... z_max): the body's surface layer facing that way, loaded at the
    // particles' face points. A named surface of the geometry (face bit kFirstSurfaceBit + k):
    // the particles preprocess tagged within one lattice spacing of it, each with the nominal
    // area spacing^(Dim-1) at its centre (exact for surfaces along the lattice; an inclined
    // surface tags more particles per length, e.g. ~41 % more at 45 degrees — docs/scene-format.md).
    const bool named = !is_axis_face(load.face);
    int f = 0;
    if (named) {
      const auto names = scene::surface_bit_names(s);
      const auto it = std::find(names.begin(), names.end(), load.face);
      if (it == names.end()) throw std::runtime_error("loads: unknown surface \"" + load.face + "\"");
      f = scene::kFirstSurfaceBit + static_cast<int>(it - names.begin());
      if (load.type == "pressure")
        throw std::runtime_error("loads: a pressure on the named surface \"" + load.face +
                                 "\" needs surface normals, not implemented yet (use a traction vector)");
    } else {
      f = face_index(load.face);
    }
    const int axis = named ? -1 : f / 2;
    const double outward = f % 2 == 0 ? -1.0 : 1.0;
    Entry e{{}, {}, {}, TimeFunction(load.function)};
    for (std::size_t p = 0; p < ps.size(); ++p) {
      if (ps.body[p] != body || !(ps.faces[p] & (1u << f))) continue;
      if (load.region) {
        bool in = true;
        for (int a = 0; a < Dim; ++a)
          in = in && ps.x0[p][a] >= load.region->first[a] && ps.x0[p][a] <= load.region->second[a];
        if (!in) continue;
      }
      // Nominal face area of the particle: its domain's extent across the face (unit thickness in 2D).
      double area = 1.0;
      for (int a = 0; a < Dim - (named ? 1 : 0); ++a)
        if (a != axis) area *= 2.0 * ps.l[p][a];
      Vec<Dim> force = Vec<Dim>::Zero();
      if (load.type == "pressure") force[axis] = -outward * load.value[0] * area;  // pushes inward
      else
        for (int a = 0; a < Dim; ++a) force[a] = load.value[a] * area;
      Vec<Dim> offset = Vec<Dim>::Zero();
      if (!named) offset[axis] = outward * ps.l[p][axis];
      e.ids.push_back(ps.id[p]);
      e.force.push_back(force);
      e.offset.push_back(offset);
    }
    entries_.push_back(std::move(e));
  }
}

template class GridBoundary<2>;
template class GridBoundary<3>;
template class ParticleLoads<2>;
template class ParticleLoads<3>;

}  // namespace swmpm
