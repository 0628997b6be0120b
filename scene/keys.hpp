// The registries (the exact strings a user writes) and the key tables of every object kind of the
// scene file (internal to swmpm_scene; how the tables are used: validate.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "scene/validate.hpp"

namespace swmpm::scene::detail {

// ------------------------------------------------------------------------------------------------
// Registries: the exact strings a user writes. Enumerations with a to_string() in scene.cpp are
// matched against it, so each of those strings exists once.
// ------------------------------------------------------------------------------------------------

inline constexpr std::array kFormulations{Formulation::dry,
                                          Formulation::explicit_single_point,
                                          Formulation::semi_implicit_single_point,
                                          Formulation::semi_implicit_double_point,
                                          Formulation::explicit_double_point,
                                          Formulation::mpm_fem,
                                          Formulation::automatic};
inline constexpr std::array kShapeFunctions{ShapeFunction::linear, ShapeFunction::gimp,
                                            ShapeFunction::bspline2, ShapeFunction::bspline3};
inline constexpr std::array kModels{MaterialModel::linear_elastic, MaterialModel::hencky,
                                    MaterialModel::mohr_coulomb,   MaterialModel::drucker_prager,
                                    MaterialModel::nor_sand,       MaterialModel::fluid};

template <class E, std::size_t N>
std::vector<std::string> names_of(const std::array<E, N>& all) {
  std::vector<std::string> out;
  for (E e : all) out.push_back(to_string(e));
  return out;
}

template <class E, std::size_t N>
std::optional<E> from_string(const std::array<E, N>& all, const std::string& s) {
  for (E e : all) {
    if (to_string(e) == s) return e;
  }
  return std::nullopt;
}

// Ordered as the enumerators of SolidBc / FluidBc: the index is the enumerator.
const std::vector<std::string>& solid_bc_names();
const std::vector<std::string>& fluid_bc_names();
const std::vector<std::string>& face_names();
const std::vector<std::string>& geometry_types();
// Quantities of one followed particle (monitor with `at` or `particle`).
const std::vector<std::string>& point_quantities();
// Quantities of the whole model (monitor with neither `at` nor `particle`).
const std::vector<std::string>& global_quantities();
const std::vector<std::string>& all_quantities();
// Components that do not exist in a 2D (plane strain) scene. stress_zz does: it is the
// out-of-plane normal stress of plane strain.
bool is_3d_only_quantity(const std::string& q);
bool needs_fluid_quantity(const std::string& q);

// -- the tables -----------------------------------------------------------------------------------

const Table& scene_table();
const Table& grid_table();
const Table& material_table();
const Table& solid_table();
const Table& elastic_table();
const Table& strength_table();
const Table& nor_sand_table();
const Table& fluid_table();
const Table& body_table();
const Table& geometry_table();
const Table& box_table();
const Table& polygon_table();
const Table& slope_table();
const Table& footing_table();
const Table& gmsh_table();
const Table& surface_mesh_table();
const Table& initial_table();
const Table& boundary_table();
const Table& load_table();
const Table& region_table();
const Table& time_table();
const Table& output_table();
const Table& monitor_table();
const Table& solver_table();
const Table& initialisation_table();
const Table& stabilisation_table();
const Table& air_table();
const Table& phase_field_table();
/// The tables of the parameters a material model's constitutive law reads (elasticity, strength,
/// Nor-Sand; none for a fluid): what initialisation.materials may override.
std::vector<const Table*> constitutive_tables(MaterialModel m);

/// Every table, in the order of the reference.
std::vector<const Table*> all_tables();
/// The parameter tables of a material model, besides material_table().
std::vector<const Table*> model_tables(MaterialModel m);

}  // namespace swmpm::scene::detail
