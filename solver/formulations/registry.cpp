#include "solver/formulations/registry.hpp"

#include "scene/formulations.hpp"

namespace swmpm {

void StageTimes::add(const char* name, double s) {
  for (std::size_t k = 0; k < names.size(); ++k)
    if (names[k] == name) {
      seconds[k] += s;
      return;
    }
  names.emplace_back(name);
  seconds.push_back(s);
}

namespace {

/// The solver of each formulation row (scene/formulations.hpp) that is implemented: one entry a
/// formulation, and tests/unit check that the two lists agree.
template <int Dim>
struct Factory {
  scene::Formulation id;
  std::unique_ptr<Formulation<Dim>> (*make)(const scene::Scene&, const State<Dim>&);
};
template <int Dim>
constexpr Factory<Dim> kFactories[] = {
    {scene::Formulation::dry, make_dry<Dim>},
    {scene::Formulation::explicit_single_point, make_explicit_single_point<Dim>},
    {scene::Formulation::semi_implicit_single_point, make_semi_implicit_single_point<Dim>},
    {scene::Formulation::semi_implicit_double_point, make_semi_implicit_double_point<Dim>},
    {scene::Formulation::explicit_double_point, make_explicit_double_point<Dim>},
    {scene::Formulation::mpm_fem, make_mpm_fem<Dim>},
};

}  // namespace

bool has_solver(scene::Formulation f) {
  for (const auto& e : kFactories<2>)
    if (e.id == f) return true;
  return false;
}

template <int Dim>
std::unique_ptr<Formulation<Dim>> make_formulation(const scene::Scene& s, const State<Dim>& state) {
  for (const auto& e : kFactories<Dim>)
    if (e.id == s.formulation) return e.make(s, state);
  throw std::runtime_error("formulation \"" + scene::to_string(s.formulation) +
                           "\" is not implemented yet in this version (available: " + scene::implemented_formulations() +
                           ")");
}

template std::unique_ptr<Formulation<2>> make_formulation<2>(const scene::Scene&, const State<2>&);
template std::unique_ptr<Formulation<3>> make_formulation<3>(const scene::Scene&, const State<3>&);

}  // namespace swmpm
