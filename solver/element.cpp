// `swmpm element`: the single-material-point driver (see element.hpp).
#include "solver/element.hpp"

#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>


#include "solver/materials/material.hpp"

namespace swmpm {
namespace {

namespace fs = std::filesystem;

/// The state a trial starts from (the model must see the same σ_n, F_n each time).
struct Saved {
  Sym sigma;
  Mat3 F;
  double eps_p;
  MaterialState state;  // the model's internal variables (Nor-Sand: π_i, Ē_d^p, ψ_start)
};

class Point {
 public:
  Point(const MaterialModel<3>& model, double p0) : model_(model) {
    ps_.resize(1);
    ps_.add_material_state();  // zero: "not initialised", as for a freshly loaded particle
    ps_.V0[0] = ps_.V[0] = 1.0;
    ps_.m[0] = 1.0;
    ps_.sigma[0] << -p0, -p0, -p0, 0.0, 0.0, 0.0;
  }
  Saved save() const { return {ps_.sigma[0], ps_.F[0], ps_.eps_p[0], ps_.state[0]}; }
  const Sym& sigma() const { return ps_.sigma[0]; }
  const Mat3& F() const { return ps_.F[0]; }
  const ParticleSet<3>& particles() const { return ps_; }

  /// From `s`, one update to the diagonal F_{n+1} = diag(f): L dt = 2 (ΔF − I)(ΔF + I)⁻¹, dt = 1,
  /// the inverse of the solver's ΔF = (I − L dt/2)⁻¹ (I + L dt/2).
  void step(const Saved& s, const std::array<double, 3>& f) {
    ps_.sigma[0] = s.sigma;
    ps_.eps_p[0] = s.eps_p;
    ps_.state[0] = s.state;
    Mat3 F = Mat3::Zero(), L = Mat3::Zero();
    for (int i = 0; i < 3; ++i) {
      F(i, i) = f[static_cast<std::size_t>(i)];
      const double r = F(i, i) / s.F(i, i);
      L(i, i) = 2.0 * (r - 1.0) / (r + 1.0);
    }
    ps_.F[0] = F;
    ps_.L[0] = L;
    ps_.V[0] = ps_.V0[0] * F.determinant();
    const int id = 0;
    if (model_.update_stress(ps_, std::span<const int>(&id, 1), 1.0) >= 0)
      throw std::runtime_error("the model failed at F = diag(" + std::to_string(f[0]) + ", " + std::to_string(f[1]) +
                               ", " + std::to_string(f[2]) + ") (J <= 0 or a non-finite stress)");
  }

 private:
  const MaterialModel<3>& model_;
  ParticleSet<3> ps_;
};

}  // namespace

ElementTest parse_element_test(const std::string& name) {
  if (name == "drained-triaxial") return ElementTest::drained_triaxial;
  if (name == "undrained-triaxial") return ElementTest::undrained_triaxial;
  if (name == "oedometer") return ElementTest::oedometer;
  throw std::invalid_argument("--test \"" + name + "\" is not one of drained-triaxial, undrained-triaxial, oedometer");
}

std::string to_string(ElementTest t) {
  switch (t) {
    case ElementTest::drained_triaxial: return "drained-triaxial";
    case ElementTest::undrained_triaxial: return "undrained-triaxial";
    case ElementTest::oedometer: return "oedometer";
  }
  return "?";
}

ElementResult run_element(const scene::Scene& scene, const std::string& material, ElementTest test, double p0,
                          double axial_strain, int steps) {
  const int index = scene.material_index(material);
  if (index < 0) {
    std::string names;
    for (const auto& m : scene.materials) names += (names.empty() ? "" : ", ") + m.name;
    throw std::invalid_argument("--material \"" + material + "\": the scene has no material of that name (its materials: " +
                                (names.empty() ? "none" : names) + ")");
  }
  const scene::Material& mat = scene.materials[static_cast<std::size_t>(index)];
  if (mat.model == scene::MaterialModel::fluid)
    throw std::invalid_argument("--material \"" + material +
                                "\" is a fluid; an element test needs a solid (soil skeleton) material");
  if (!(p0 > 0.0) || !std::isfinite(p0)) throw std::invalid_argument("--p0 must be a positive stress [Pa]");
  if (!(std::abs(axial_strain) < 1.0)) throw std::invalid_argument("--axial-strain must lie in (-1, 1)");
  if (steps < 1) throw std::invalid_argument("--steps must be at least 1");

  const auto model = make_material<3>(mat, scene);
  Point pt(*model, p0);
  ElementResult r;
  r.material = material;
  r.model = model->name();
  r.test = test;
  r.p0 = p0;
  r.state_names = model->report_names();
  r.state_columns.resize(r.state_names.size());
  std::vector<double> values(r.state_names.size());
  const auto record = [&] {
    const Sym& s = pt.sigma();
    const Mat3& F = pt.F();
    const double sa = -s[2], sr = -0.5 * (s[0] + s[1]);
    r.axial_strain.push_back(1.0 - F(2, 2));
    r.p.push_back(-(s[0] + s[1] + s[2]) / 3.0);
    r.q.push_back(sa - sr);
    r.volumetric_strain.push_back(1.0 - F.determinant());
    r.axial_stress.push_back(sa);
    r.radial_stress.push_back(sr);
    r.radial_strain.push_back(1.0 - F(0, 0));
    model->report_values(pt.particles(), 0, values);
    for (std::size_t c = 0; c < values.size(); ++c) r.state_columns[c].push_back(values[c]);
  };
  record();

  double lateral = 1.0;  // drained: F_xx = F_yy of the last converged step
  for (int k = 1; k <= steps; ++k) {
    const double lam = 1.0 - axial_strain * k / steps;
    const Saved s = pt.save();
    switch (test) {
      case ElementTest::oedometer: pt.step(s, {1.0, 1.0, lam}); break;
      case ElementTest::undrained_triaxial: {
        const double f = 1.0 / std::sqrt(lam);
        pt.step(s, {f, f, lam});
        break;
      }
      case ElementTest::drained_triaxial: {
        // Newton on F_xx = F_yy = x for the residual σ_xx + p0 (σ_yy equals σ_xx by symmetry),
        // first guess: the lateral stretch ratio of the last step.
        const double lam_prev = 1.0 - axial_strain * (k - 1) / steps;
        double x = lateral * (r.size() > 1 ? std::pow(lam / lam_prev, -0.5) : 1.0);
        if (!(x > 0.0) || !std::isfinite(x)) x = lateral;
        const auto residual = [&](double xx) {
          pt.step(s, {xx, xx, lam});
          return (pt.sigma()[0] + pt.sigma()[1]) / 2.0 + p0;
        };
        const double tol = 1e-10 * p0;
        double R = residual(x);
        int it = 0;
        for (; std::abs(R) > tol && it < 60; ++it) {
          const double h = 1e-7 * x;
          const double dR = (residual(x + h) - R) / h;
          if (!(std::abs(dR) > 0.0) || !std::isfinite(dR))
            throw std::runtime_error("drained triaxial: zero lateral stiffness at axial strain " +
                                     std::to_string(1.0 - lam) + " (the material cannot hold the confining stress)");
          double dx = -R / dR;
          const double cap = 0.05 * x;  // no wild jumps; Newton is back within a few iterations
          if (std::abs(dx) > cap) dx = dx > 0 ? cap : -cap;
          x += dx;
          R = residual(x);
        }
        if (std::abs(R) > tol)
          throw std::runtime_error("drained triaxial: the lateral stress iteration did not converge at axial strain " +
                                   std::to_string(1.0 - lam) + " (residual " + std::to_string(R) + " Pa)");
        lateral = x;
        break;
      }
    }
    record();
  }
  return r;
}


}  // namespace swmpm
