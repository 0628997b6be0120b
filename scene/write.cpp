// Writing a scene back: to_json, the resolved scene (every default filled in, `auto` resolved) that
// preprocess writes to RUN_DIR/scene.json and that parses back to the same scene.
#include <algorithm>

#include "scene/formulations.hpp"
#include "scene/keys.hpp"

namespace swmpm::scene {

using namespace detail;

// ------------------------------------------------------------------------------------------------
// Writing a scene back.
// ------------------------------------------------------------------------------------------------

namespace {

json vec_json(const Vec3& v, int dim) {
  json a = json::array();
  for (int d = 0; d < dim; ++d) a.push_back(v[static_cast<std::size_t>(d)]);
  return a;
}

/// The resolved geometry of the types beyond box and polygon: defaults written out (slope
/// `origin`), footing `on` resolved to `base_y`, file paths absolute.
json geometry_json(const Geometry& g, int dim) {
  if (g.type == "slope") {
    json j = {{"type", "slope"},          {"foundation_depth", g.foundation_depth}, {"height", g.height},
              {"crest_length", g.crest_length}, {"toe_length", g.toe_length},
              {"origin", {g.origin[0], g.origin[1]}}};
    if (g.ratio > 0.0) j["ratio"] = g.ratio;
    else j["angle"] = g.angle;
    return j;
  }
  if (g.type == "footing") {
    json j = {{"type", "footing"}, {"width", g.width}, {"height", g.height}, {"center_x", g.center_x},
              {"base_y", g.base_y}};
    if (dim == 3) {
      j["center_z"] = g.center_z;
      j["length"] = g.length;
    }
    return j;
  }
  if (g.type == "gmsh") {
    json j = {{"type", "gmsh"}, {"file", g.file}, {"parameters", json::object()}};
    for (const auto& [name, value] : g.parameters) j["parameters"][name] = value;
    if (!g.physical.empty()) j["physical"] = g.physical;
    return j;
  }
  if (g.type == "surface-mesh") return {{"type", "surface-mesh"}, {"file", g.file}};
  return g.raw;
}

}  // namespace

bool reads_switch(const Scene& s, const std::string& key) {
  if (key == "strain_smoothing") return row_of(s.formulation).find("/solver/stabilisation/strain_smoothing") != nullptr;
  if (key == "pressure") return row_of(s.formulation).find("/solver/stabilisation/pressure") != nullptr;
  if (key == "fbar_patch") return s.solver.stabilisation.fbar == "modified";
  if (key == "kinematics") {
    // mohr-coulomb, drucker-prager and nor-sand read it (drucker-prager, nor-sand: finite strain
    // only), in every formulation; the other models follow their own kinematics (linear-elastic:
    // Jaumann rate, hencky: finite).
    for (const auto& m : s.materials)
      if (m.model == MaterialModel::mohr_coulomb || m.model == MaterialModel::drucker_prager ||
          m.model == MaterialModel::nor_sand)
        return true;
    return false;
  }
  return true;
}

nlohmann::json to_json(const Scene& s) {
  const int dim = s.dimension;
  json j;
  j["name"] = s.name;
  j["dimension"] = dim;
  j["formulation"] = to_string(s.formulation);
  if (s.formulation_choice.is_object()) j["formulation_choice"] = s.formulation_choice;  // "auto": how it chose
  j["gravity"] = vec_json(s.gravity, dim);
  j["gravity_ramp"] = s.gravity_ramp;
  j["grid"] = {{"cell_size", s.grid.cell_size},
               {"min", vec_json(s.grid.min, dim)},
               {"max", vec_json(s.grid.max, dim)},
               {"shape_function", to_string(s.grid.shape_function)}};

  j["materials"] = json::array();
  for (const Material& m : s.materials) {
    json mj = {{"name", m.name}, {"model", to_string(m.model)}};
    // Keys only some formulations read (their defaults included) are written for those only.
    const auto& own = row_of(s.formulation).material_keys;
    for (const auto& [key, value] : m.params) {
      bool other = false;
      for (const FormulationRow& r : formulation_rows())
        other = other || std::find(r.material_keys.begin(), r.material_keys.end(), key) != r.material_keys.end();
      if (other && std::find(own.begin(), own.end(), key) == own.end()) continue;
      mj[key] = value;
    }
    if (m.model != MaterialModel::fluid) mj["permeability_law"] = m.permeability_law;
    j["materials"].push_back(mj);
  }

  j["bodies"] = json::array();
  for (const Body& b : s.bodies) {
    json bj = {{"name", b.name}, {"particles_per_cell", b.particles_per_cell}};
    const Geometry& g = b.geometry;
    if (g.type == "box") {
      bj["geometry"] = {{"type", "box"}, {"min", vec_json(g.min, dim)}, {"max", vec_json(g.max, dim)}};
    } else if (g.type == "polygon") {
      json vs = json::array();
      for (const auto& v : g.vertices) vs.push_back({v[0], v[1]});
      bj["geometry"] = {{"type", "polygon"}, {"vertices", vs}};
    } else {
      bj["geometry"] = geometry_json(g, dim);
    }
    if (!b.solid.empty()) bj["solid"] = b.solid;
    if (!b.fluid.empty()) bj["fluid"] = b.fluid;
    const InitialState& in = b.initial;
    json ij = json::object();
    if (in.hydrostatic) ij["pore_pressure"] = "hydrostatic";
    else if (in.pore_pressure) ij["pore_pressure"] = *in.pore_pressure;
    if (in.water_table) ij["water_table"] = *in.water_table;
    if (in.geostatic) {
      ij["stress"] = "geostatic";
      ij["k0"] = in.k0;
    } else if (in.stress) {
      ij["stress"] = *in.stress;
    }
    if (in.porosity) ij["porosity"] = *in.porosity;
    ij["velocity"] = json::array();
    for (int d = 0; d < dim; ++d) ij["velocity"].push_back(in.velocity[static_cast<std::size_t>(d)]);
    bj["initial"] = ij;
    j["bodies"].push_back(bj);
  }

  j["boundaries"] = json::array();
  for (const Boundary& bc : s.boundaries) {
    json bj = {{"on", bc.on}, {"solid", solid_bc_names()[static_cast<std::size_t>(bc.solid)]}};
    if (bc.solid == SolidBc::friction) bj["coefficient"] = bc.coefficient;
    if (bc.fluid) {
      bj["fluid"] = fluid_bc_names()[static_cast<std::size_t>(*bc.fluid)];
      if (*bc.fluid == FluidBc::pressure) bj["value"] = bc.fluid_value;
    }
    j["boundaries"].push_back(bj);
  }

  j["loads"] = json::array();
  for (const Load& l : s.loads) {
    json lj = {{"type", l.type}, {"body", l.body}, {"face", l.face}, {"ramp", l.function.ramp}};
    lj["value"] = l.type == "pressure" ? json(l.value[0]) : vec_json(l.value, dim);
    if (l.region) lj["region"] = {{"min", vec_json(l.region->first, dim)}, {"max", vec_json(l.region->second, dim)}};
    if (!l.function.expression.empty()) lj["function"] = l.function.expression;
    if (!l.function.table.empty()) lj["table"] = l.function.table;
    j["loads"].push_back(lj);
  }

  if (s.initialisation.enabled()) {
    const Initialisation& in = s.initialisation;
    json ij = {{"duration", in.duration}, {"gravity_ramp", in.gravity_ramp}, {"plasticity", in.plasticity},
               {"reset_displacement", in.reset_displacement}};
    if (in.hydraulic_conductivity) ij["hydraulic_conductivity"] = *in.hydraulic_conductivity;
    if (in.damping) ij["damping"] = *in.damping;
    if (row_of(s.formulation).find("/initialisation/tie_water")) ij["tie_water"] = in.tie_water;
    if (!in.materials.empty()) ij["materials"] = in.materials;  // name -> {parameter: value}
    j["initialisation"] = ij;
  }

  j["time"] = {{"end", s.time.end}, {"cfl", s.time.cfl}};
  j["time"]["dt"] = s.time.dt ? json(*s.time.dt) : json("auto");

  json monitors = json::array();
  for (const Monitor& m : s.output.monitors) {
    json mj = {{"name", m.name}, {"quantities", m.quantities}};
    if (m.gauge) {  // a water_level gauge: its vertical line, [x] or [x, z]; no phase
      mj["at"] = dim == 2 ? json::array({(*m.gauge)[0]}) : json::array({(*m.gauge)[0], (*m.gauge)[2]});
      monitors.push_back(mj);
      continue;
    }
    mj["phase"] = m.phase;
    if (m.at) mj["at"] = vec_json(*m.at, dim);
    if (m.particle) mj["particle"] = *m.particle;
    if (m.points != "soil") mj["points"] = m.points;
    monitors.push_back(mj);
  }
  j["output"] = {{"interval", s.output.interval},
                 {"monitor_interval", s.output.monitor_interval},
                 {"compression", s.output.compression},
                 {"monitors", monitors}};
  if (s.output.checkpoint_interval) j["output"]["checkpoint_interval"] = *s.output.checkpoint_interval;

  const Solver& sv = s.solver;
  j["solver"] = {{"flip", sv.flip},
                 {"damping", sv.damping},
                 {"checkpoint_every", sv.checkpoint_every},
                 {"stabilisation", {{"fbar", sv.stabilisation.fbar}}}};
  if (reads_switch(s, "kinematics")) j["solver"]["kinematics"] = sv.kinematics;
  json& stab = j["solver"]["stabilisation"];
  if (reads_switch(s, "strain_smoothing")) stab["strain_smoothing"] = sv.stabilisation.strain_smoothing;
  if (reads_switch(s, "pressure")) stab["pressure"] = sv.stabilisation.pressure;
  if (reads_switch(s, "fbar_patch")) stab["fbar_patch"] = sv.stabilisation.fbar_patch;
  // The formulation-specific switches of the scene's formulation (scene/formulations.hpp).
  const FormulationRow& row = row_of(s.formulation);
  if (row.find("/solver/continuity")) j["solver"]["continuity"] = sv.continuity;
  if (row.find("/solver/escaped_water")) j["solver"]["escaped_water"] = sv.escaped_water;
  if (row.find("/solver/drag_integration")) j["solver"]["drag_integration"] = sv.drag_integration;
  if (row.find("/solver/drag")) j["solver"]["drag"] = sv.drag;
  if (row.reads("/solver/soil_substeps")) j["solver"]["soil_substeps"] = sv.soil_substeps;
  if (row.reads("/solver/air"))
    j["solver"]["air"] = {{"density", sv.air.density},
                          {"dynamic_viscosity", sv.air.dynamic_viscosity},
                          {"domain", sv.air.whole_grid ? "grid" : "active"}};
  if (row.reads("/solver/phase_field")) {  // an absent value stays absent: the solver's choice
    json pf = json::object();
    if (sv.phase_field.interface_width) pf["interface_width"] = *sv.phase_field.interface_width;
    if (sv.phase_field.mobility) pf["mobility"] = *sv.phase_field.mobility;
    pf["lsic"] = sv.phase_field.lsic;
    pf["volume_correction"] = sv.phase_field.volume_correction;
    j["solver"]["phase_field"] = pf;
  }
  return j;
}

}  // namespace swmpm::scene
