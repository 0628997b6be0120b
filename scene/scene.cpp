// The scene model's small behaviours: lookups, derived values and the exact user strings of the
// enumerations. The strings here are the registry keys of the scene file (style.md item 4): the
// parser matches what the user wrote against to_string() of every enumerator, so each string is
// written exactly once, here.
#include "scene/scene.hpp"

#include <algorithm>

namespace swmpm::scene {

namespace {

std::string join_lines(const std::vector<std::string>& lines) {
  std::string out;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (i > 0) out += '\n';
    out += lines[i];
  }
  return out;
}

}  // namespace

SceneError::SceneError(std::vector<std::string> lines)
    : std::runtime_error(join_lines(lines)), lines_(std::move(lines)) {}

double Material::at(const std::string& key) const {
  const auto it = params.find(key);
  if (it == params.end()) {
    throw std::out_of_range("material \"" + name + "\" (model \"" + to_string(model) +
                            "\") has no parameter \"" + key + "\"");
  }
  return it->second;
}

double Material::solid_bulk_density() const {
  // A dry body states its density directly; a porous skeleton contributes (1 - n) rho_s.
  if (has("density")) return at("density");                         // kg/m^3
  return (1.0 - at("porosity")) * at("grain_density");               // kg/m^3
}

const Material& Scene::material(const std::string& material_name) const {
  const int i = material_index(material_name);
  if (i < 0) throw std::out_of_range("scene has no material named \"" + material_name + "\"");
  return materials[static_cast<std::size_t>(i)];
}

int Scene::material_index(const std::string& material_name) const {
  for (std::size_t i = 0; i < materials.size(); ++i) {
    if (materials[i].name == material_name) return static_cast<int>(i);
  }
  return -1;
}

bool Scene::has_fluid() const {
  return std::any_of(bodies.begin(), bodies.end(), [](const Body& b) { return !b.fluid.empty(); });
}

std::string to_string(Formulation f) {
  switch (f) {
    case Formulation::dry: return "dry";
    case Formulation::explicit_single_point: return "explicit-single-point";
    case Formulation::semi_implicit_single_point: return "semi-implicit-single-point";
    case Formulation::semi_implicit_double_point: return "semi-implicit-double-point";
    case Formulation::explicit_double_point: return "explicit-double-point";
    case Formulation::mpm_fem: return "mpm-fem";
    case Formulation::automatic: return "auto";
  }
  return "?";
}

std::string to_string(ShapeFunction f) {
  switch (f) {
    case ShapeFunction::linear: return "linear";
    case ShapeFunction::gimp: return "gimp";
    case ShapeFunction::bspline2: return "bspline2";
    case ShapeFunction::bspline3: return "bspline3";
  }
  return "?";
}

double default_fbar_patch(ShapeFunction f) {
  return f == ShapeFunction::bspline2 || f == ShapeFunction::bspline3 ? 1.5 : 1.0;
}

std::string to_string(MaterialModel m) {
  switch (m) {
    case MaterialModel::linear_elastic: return "linear-elastic";
    case MaterialModel::hencky: return "hencky";
    case MaterialModel::mohr_coulomb: return "mohr-coulomb";
    case MaterialModel::drucker_prager: return "drucker-prager";
    case MaterialModel::nor_sand: return "nor-sand";
    case MaterialModel::fluid: return "fluid";
  }
  return "?";
}

}  // namespace swmpm::scene
