#include "solver/output/particle_io.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace swmpm {

template <int Dim>
ParticleSet<Dim> particles_from_cloud(const scene::PointCloud& c, const std::string& where) {
  ParticleSet<Dim> ps;
  const std::size_t n = c.size();
  ps.resize(n);
  const auto& id = c.get("id", where);
  const auto& mass = c.get("mass", where);
  const auto& volume = c.get("volume", where);
  const auto& half = c.get("half_size", where);
  const auto& vel = c.get("velocity", where);
  // Double-point water points (particles/fluid.vtu) carry no effective stress; every other set does.
  const bool water_points = c.find("pore_pressure") != nullptr && c.find("fluid_mass") == nullptr;
  const auto* stress = water_points ? c.find("stress") : &c.get("stress", where);
  const auto& material = c.get("material", where);
  const auto& body = c.get("body", where);
  const auto& faces = c.get("faces", where);
  const auto* disp = c.find("displacement");
  const auto* eps_p = c.find("plastic_strain");
  // Single-point two-phase sets carry the pore fluid on the same points (pore_pressure,
  // porosity, fluid_mass, fluid_material). Double-point sets: the soil points carry the porosity
  // only, the water points the pore pressure and porosity; both get the pore-fluid arrays (the
  // formulation fills what the file lacks: fluid mass, fluid material -1 = the body's fluid).
  const auto* pore_pressure = c.find("pore_pressure");
  const bool single_point = pore_pressure != nullptr && !water_points;
  const bool two_phase = single_point || c.find("porosity") != nullptr;
  const auto* porosity = two_phase ? &c.get("porosity", where) : nullptr;
  const auto* fluid_mass = single_point ? &c.get("fluid_mass", where) : nullptr;
  const auto* fluid_material = single_point ? &c.get("fluid_material", where) : nullptr;
  const auto* fluid_velocity = c.find("fluid_velocity");
  if (two_phase) ps.add_fluid();
  for (std::size_t p = 0; p < n; ++p) {
    ps.id[p] = static_cast<std::int64_t>(id.values[p]);
    for (int a = 0; a < Dim; ++a) {
      ps.x[p][a] = c.points[p][a];
      ps.x0[p][a] = c.points[p][a] - (disp ? disp->values[3 * p + a] : 0.0);
      ps.v[p][a] = vel.values[3 * p + a];
      ps.l[p][a] = half.values[3 * p + a];
    }
    ps.m[p] = mass.values[p];
    ps.V[p] = ps.V0[p] = volume.values[p];
    if (stress)
      for (int k = 0; k < 6; ++k) ps.sigma[p][k] = stress->values[6 * p + k];
    ps.material[p] = static_cast<std::int32_t>(material.values[p]);
    ps.body[p] = static_cast<std::int32_t>(body.values[p]);
    ps.faces[p] = static_cast<std::uint32_t>(faces.values[p]);
    if (eps_p) ps.eps_p[p] = eps_p->values[p];
    if (two_phase) {
      ps.n[p] = porosity->values[p];
      ps.p[p] = pore_pressure ? pore_pressure->values[p] : 0.0;
      ps.m_f[p] = fluid_mass ? fluid_mass->values[p] : 0.0;
      ps.fluid_material[p] = fluid_material ? static_cast<std::int32_t>(fluid_material->values[p]) : -1;
      for (int a = 0; a < Dim; ++a) ps.v_f[p][a] = fluid_velocity ? fluid_velocity->values[3 * p + a] : ps.v[p][a];
    }
    if (!(ps.m[p] > 0.0) || !(ps.V[p] > 0.0))
      throw std::runtime_error(where + ": particle " + std::to_string(ps.id[p]) +
                               " has non-positive mass or volume");
  }
  return ps;
}

template <int Dim>
scene::PointCloud particles_to_cloud(const ParticleSet<Dim>& ps) {
  scene::PointCloud c;
  const std::size_t n = ps.size();
  c.points.resize(n);
  for (std::size_t p = 0; p < n; ++p) {
    c.points[p] = {0, 0, 0};
    for (int a = 0; a < Dim; ++a) c.points[p][a] = ps.x[p][a];
  }
  auto& id = c.add("id", 1);
  auto& mass = c.add("mass", 1);
  auto& volume = c.add("volume", 1);
  auto& half = c.add("half_size", 3);
  auto& vel = c.add("velocity", 3);
  auto& disp = c.add("displacement", 3);
  auto& stress = c.add("stress", 6);
  auto& p_mean = c.add("mean_effective_stress", 1);
  auto& q = c.add("deviatoric_stress", 1);
  auto& eps_p = c.add("plastic_strain", 1);
  auto& J = c.add("volume_ratio", 1);
  auto& material = c.add("material", 1);
  auto& body = c.add("body", 1);
  auto& faces = c.add("faces", 1);
  if (ps.two_phase()) {
    auto& pore = c.add("pore_pressure", 1);
    auto& por = c.add("porosity", 1);
    auto& mf = c.add("fluid_mass", 1);
    auto& vf = c.add("fluid_velocity", 3);
    auto& fm = c.add("fluid_material", 1);
    for (std::size_t p = 0; p < n; ++p) {
      pore.values[p] = ps.p[p];
      por.values[p] = ps.n[p];
      mf.values[p] = ps.m_f[p];
      fm.values[p] = ps.fluid_material[p];
      for (int a = 0; a < Dim; ++a) vf.values[3 * p + a] = ps.v_f[p][a];
    }
  }
  for (std::size_t p = 0; p < n; ++p) {
    id.values[p] = static_cast<double>(ps.id[p]);
    mass.values[p] = ps.m[p];
    volume.values[p] = ps.V[p];
    for (int a = 0; a < Dim; ++a) {
      half.values[3 * p + a] = ps.l[p][a];
      vel.values[3 * p + a] = ps.v[p][a];
      disp.values[3 * p + a] = ps.x[p][a] - ps.x0[p][a];
    }
    for (int k = 0; k < 6; ++k) stress.values[6 * p + k] = ps.sigma[p][k];
    p_mean.values[p] = mean_stress(ps.sigma[p]);
    q.values[p] = deviatoric_stress(ps.sigma[p]);
    eps_p.values[p] = ps.eps_p[p];
    J.values[p] = ps.V[p] / ps.V0[p];
    material.values[p] = ps.material[p];
    body.values[p] = ps.body[p];
    faces.values[p] = ps.faces[p];
  }
  return c;
}

template <int Dim>
scene::PointCloud water_points_to_cloud(const ParticleSet<Dim>& ws) {
  scene::PointCloud c;
  const std::size_t n = ws.size();
  c.points.resize(n);
  auto& id = c.add("id", 1);
  auto& mass = c.add("mass", 1);
  auto& volume = c.add("volume", 1);
  auto& vel = c.add("velocity", 3);
  auto& disp = c.add("displacement", 3);
  auto& pore = c.add("pore_pressure", 1);
  auto& por = c.add("porosity", 1);
  auto& material = c.add("material", 1);
  auto& body = c.add("body", 1);
  for (std::size_t p = 0; p < n; ++p) {
    c.points[p] = {0, 0, 0};
    for (int a = 0; a < Dim; ++a) {
      c.points[p][a] = ws.x[p][a];
      vel.values[3 * p + a] = ws.v[p][a];
      disp.values[3 * p + a] = ws.x[p][a] - ws.x0[p][a];
    }
    id.values[p] = static_cast<double>(ws.id[p]);
    mass.values[p] = ws.m[p];
    volume.values[p] = ws.V[p];
    pore.values[p] = ws.p[p];
    por.values[p] = ws.n[p];
    material.values[p] = ws.material[p];
    body.values[p] = ws.body[p];
  }
  return c;
}

template <int Dim>
SurfaceSamples<Dim> surface_samples_from_cloud(const scene::PointCloud& c, const std::string& where) {
  SurfaceSamples<Dim> out;
  const auto& surface = c.get("surface", where);
  const auto& body = c.get("body", where);
  const auto& normal = c.get("normal", where);
  const auto& area = c.get("area", where);
  for (std::size_t j = 0; j < c.size(); ++j) {
    Vec<Dim> x, n;
    for (int a = 0; a < Dim; ++a) {
      x[a] = c.points[j][a];
      n[a] = normal.values[3 * j + a];
    }
    out.surface.push_back(static_cast<int>(surface.values[j]));
    out.body.push_back(static_cast<int>(body.values[j]));
    out.x.push_back(x);
    out.normal.push_back(n);
    out.area.push_back(area.values[j]);
  }
  return out;
}

template scene::PointCloud water_points_to_cloud<2>(const ParticleSet<2>&);
template scene::PointCloud water_points_to_cloud<3>(const ParticleSet<3>&);
template SurfaceSamples<2> surface_samples_from_cloud<2>(const scene::PointCloud&, const std::string&);
template SurfaceSamples<3> surface_samples_from_cloud<3>(const scene::PointCloud&, const std::string&);
template ParticleSet<2> particles_from_cloud<2>(const scene::PointCloud&, const std::string&);
template ParticleSet<3> particles_from_cloud<3>(const scene::PointCloud&, const std::string&);
template <int Dim>
void add_material_reports(scene::PointCloud& c, const ParticleSet<Dim>& ps,
                          const std::vector<std::unique_ptr<MaterialModel<Dim>>>& models) {
  // Per material: the cloud array of each of its report names (shared when two materials report
  // the same name).
  std::vector<std::vector<scene::PointArray*>> arrays(models.size());
  for (std::size_t k = 0; k < models.size(); ++k) {
    if (!models[k]) continue;
    for (const auto& name : models[k]->report_names()) {
      scene::PointArray* a = nullptr;
      for (auto& existing : c.arrays)
        if (existing.name == name) a = &existing;
      if (!a) {
        a = &c.add(name, 1);
        std::fill(a->values.begin(), a->values.end(), std::numeric_limits<double>::quiet_NaN());
      }
      arrays[k].push_back(a);
    }
  }
  std::vector<double> values;
  for (std::size_t p = 0; p < ps.size(); ++p) {
    const std::size_t k = static_cast<std::size_t>(ps.material[p]);
    if (k >= models.size() || arrays[k].empty()) continue;
    values.assign(arrays[k].size(), 0.0);
    models[k]->report_values(ps, static_cast<int>(p), values);
    for (std::size_t j = 0; j < values.size(); ++j) arrays[k][j]->values[p] = values[j];
  }
}

template scene::PointCloud particles_to_cloud<2>(const ParticleSet<2>&);
template scene::PointCloud particles_to_cloud<3>(const ParticleSet<3>&);
template void add_material_reports<2>(scene::PointCloud&, const ParticleSet<2>&,
                                      const std::vector<std::unique_ptr<MaterialModel<2>>>&);
template void add_material_reports<3>(scene::PointCloud&, const ParticleSet<3>&,
                                      const std::vector<std::unique_ptr<MaterialModel<3>>>&);

}  // namespace swmpm
