#include "solver/formulations/registry.hpp"

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

template <int Dim>
std::unique_ptr<Formulation<Dim>> make_formulation(const scene::Scene& s, const State<Dim>& state) {
  switch (s.formulation) {
    case scene::Formulation::dry: return make_dry<Dim>(s, state);
    case scene::Formulation::explicit_single_point: return make_explicit_single_point<Dim>(s, state);
    case scene::Formulation::semi_implicit_single_point: return make_semi_implicit_single_point<Dim>(s, state);
    case scene::Formulation::semi_implicit_double_point: return make_semi_implicit_double_point<Dim>(s, state);
    default:
      throw std::runtime_error("formulation \"" + scene::to_string(s.formulation) +
                               "\" is not implemented yet in this version (available: dry, explicit-single-point, semi-implicit-single-point, semi-implicit-double-point)");
  }
}

template std::unique_ptr<Formulation<2>> make_formulation<2>(const scene::Scene&, const State<2>&);
template std::unique_ptr<Formulation<3>> make_formulation<3>(const scene::Scene&, const State<3>&);

}  // namespace swmpm
