#include "solver/output/monitors.hpp"

#include "solver/parallel/comm.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <span>
#include <sstream>
#include <stdexcept>

#include "scene/formulations.hpp"

namespace swmpm {
namespace {

/// The id of the point nearest a monitor's place over every rank's points (-1: no point): this
/// rank's nearest is `particle` at squared distance d2; ties go to the first in the one-rank order
/// (the lower key), as one rank's search keeps its first. Collective.
template <int Dim>
std::int64_t nearest_over_ranks(const ParticleSet<Dim>& ps, int particle, double d2) {
  if (!parallel::distributed()) return particle < 0 ? -1 : ps.id[static_cast<std::size_t>(particle)];
  const double best = parallel::min(particle < 0 ? std::numeric_limits<double>::max() : d2);
  const bool candidate = particle >= 0 && d2 == best;
  const std::size_t p = static_cast<std::size_t>(std::max(particle, 0));
  constexpr long unplaced = std::numeric_limits<long>::max();
  return parallel::value_at_lowest(candidate ? static_cast<long>(ps.place(p)) : unplaced,
                                   candidate ? static_cast<long>(ps.id[p]) : -1L, -1L, unplaced);
}

}  // namespace

template <int Dim>
Monitors<Dim>::Monitors(const scene::Scene& s, const State<Dim>& st, const Formulation<Dim>& f,
                        const std::filesystem::path& path, const std::string& header_comment,
                        std::optional<std::size_t> resume_bytes) {
  std::ostringstream header;
  header << "time";
  reach_ = 0.5 * s.grid.cell_size * (1.0 + 1e-9);  // h/2, with round-off
  for (std::size_t k = 0; k < s.output.monitors.size(); ++k) {
    const auto& mon = s.output.monitors[k];
    const std::string where = "/output/monitors/" + std::to_string(k);
    if (mon.gauge) {  // a water_level gauge: no particle; the parser allows water_level alone here
      const scene::WaterLayout& w = scene::row_of(s.formulation).water;
      const bool grid = w.free_water_on_grid && f.fluid_on_grid();  // mpm-fem: the phase field
      if (!w.fluid_particles && !grid)
        throw std::runtime_error(where + "/quantities: \"water_level\" needs liquid points (a double-point "
                                 "formulation) or a fluid on the grid (mpm-fem)");
      monitor_particle_.push_back(-1);
      monitor_x0_.push_back({0.0, 0.0, 0.0});
      monitor_water_.push_back(0);
      monitor_gauge_.push_back(static_cast<int>(gauges_.size()));
      monitor_probe_.push_back(-1);
      names_.push_back(mon.name);
      for (const auto& qn : mon.quantities) {
        if (qn != "water_level")
          throw std::runtime_error(where + "/quantities: \"" + qn + "\" is not available in a water_level gauge");
        columns_.push_back({-1, Q::level, static_cast<int>(gauges_.size())});
        header << "," << mon.name << "." << qn;
      }
      gauges_.push_back({(*mon.gauge)[0], (*mon.gauge)[2], grid});
      continue;
    }
    if (mon.at && mon.phase == "fluid" && f.fluid_on_grid()) {  // an Eulerian probe of the grid's fluid
      const int k_probe = static_cast<int>(probes_.size());
      monitor_particle_.push_back(-1);
      monitor_x0_.push_back({0.0, 0.0, 0.0});
      monitor_water_.push_back(0);
      monitor_gauge_.push_back(-1);
      monitor_probe_.push_back(k_probe);
      names_.push_back(mon.name);
      static constexpr GridQuantity velocity[] = {GridQuantity::velocity_x, GridQuantity::velocity_y,
                                                  GridQuantity::velocity_z};
      for (const auto& qn : mon.quantities) {
        const auto xyz = std::string("xyz").find(qn.back());
        if (qn == "pore_pressure")
          columns_.push_back({-1, Q::probe, k_probe, false, GridQuantity::pressure});
        else if (qn.rfind("velocity_", 0) == 0 && xyz != std::string::npos && static_cast<int>(xyz) < Dim)
          columns_.push_back({-1, Q::probe, k_probe, false, velocity[xyz]});
        else
          throw std::runtime_error(where + "/quantities: \"" + qn + "\" is not available at a fixed point of the "
                                   "grid's fluid (an Eulerian probe records pore_pressure and velocity_*; follow a "
                                   "soil point with \"phase\": \"solid\" for the others)");
        header << "," << mon.name << "." << qn;
      }
      probes_.push_back(*mon.at);
      probe_reads_.push_back(mon.quantities);
      continue;
    }
    // A water point of the double-point set, or a soil point. Single-point two-phase sets carry
    // both phases on one point: phase "fluid" reads its fluid fields (velocity, pore pressure).
    const bool water = mon.points == "water";
    if (water && parallel::sum(static_cast<long>(st.fluid.size())) == 0)  // over every rank's points
      throw std::runtime_error(where + "/points: \"water\" needs water points (a double-point formulation)");
    const auto& ps = water ? st.fluid : st.solid;
    int particle = -1;
    const bool fluid_phase = mon.phase == "fluid";
    if (fluid_phase && !water && !ps.two_phase())
      throw std::runtime_error(where + "/phase: \"fluid\" is not available in this formulation");
    std::int64_t pid = -1;
    if (mon.at) {
      double best = std::numeric_limits<double>::max();
      for (std::size_t p = 0; p < ps.size(); ++p) {
        double d2 = 0.0;
        for (int a = 0; a < Dim; ++a) d2 += (ps.x0[p][a] - (*mon.at)[a]) * (ps.x0[p][a] - (*mon.at)[a]);
        if (d2 < best) {
          best = d2;
          particle = static_cast<int>(p);
        }
      }
      pid = nearest_over_ranks(ps, particle, best);
    } else if (mon.particle) {
      for (std::size_t p = 0; p < ps.size(); ++p)
        if (ps.id[p] == *mon.particle) particle = static_cast<int>(p);
      if (!parallel::any(particle >= 0))  // over every rank's points
        throw std::runtime_error(where + "/particle: no " + (water ? "water point" : "solid particle") + " has id " +
                                 std::to_string(*mon.particle));
      pid = *mon.particle;
    }
    // Columns refer to the particle by id: formulations may reorder particles (State::index_of_id).
    monitor_particle_.push_back(pid);
    monitor_water_.push_back(water && pid >= 0);
    std::array<double, 3> x0;  // the followed point's start, from the rank that holds it (the others add -0)
    x0.fill(parallel::distributed() ? -0.0 : 0.0);
    for (std::size_t p = 0; pid >= 0 && p < ps.size(); ++p)
      if (ps.id[p] == pid)
        for (int a = 0; a < Dim; ++a) x0[static_cast<std::size_t>(a)] = ps.x0[p][a];
    if (parallel::distributed()) parallel::sum(std::span<double>(x0));
    monitor_x0_.push_back(x0);
    monitor_gauge_.push_back(-1);
    monitor_probe_.push_back(-1);
    names_.push_back(mon.name);
    for (const auto& qn : mon.quantities) {
      Column c{pid, Q::disp, 0};
      const auto xyz = std::string("xyz").find(qn.back());
      const int comp = xyz == std::string::npos || static_cast<int>(xyz) >= Dim ? -1 : static_cast<int>(xyz);
      if (qn.rfind("displacement_", 0) == 0) c = {pid, Q::disp, comp};
      else if (qn.rfind("velocity_", 0) == 0) c = {pid, fluid_phase && !water ? Q::vel_fluid : Q::vel, comp};
      else if (qn == "pore_pressure" && (water || ps.two_phase())) c = {pid, Q::pore, 0};
      else if (qn == "porosity" && (water || ps.two_phase())) c = {pid, Q::porosity, 0};
      else if (water && pid >= 0)
        throw std::runtime_error(where + "/quantities: \"" + qn + "\" is not available on a water point (displacement_*, "
                                 "velocity_*, pore_pressure, porosity are)");
      else if (qn.rfind("stress_", 0) == 0) {
        static const char* names[] = {"xx", "yy", "zz", "xy", "yz", "xz"};
        int idx = -1;
        for (int i = 0; i < 6; ++i)
          if (qn.substr(7) == names[i]) idx = i;
        c = {pid, Q::stress, idx};
      } else if (qn == "mean_effective_stress") c = {pid, Q::p_mean, 0};
      else if (qn == "deviatoric_stress") c = {pid, Q::q_dev, 0};
      else if (qn == "plastic_strain") c = {pid, Q::eps_p, 0};
      else if (qn == "kinetic_energy") c = {-1, Q::kinetic, 0};
      else if (qn == "strain_energy") c = {-1, Q::strain, 0};
      else if (qn == "total_energy") c = {-1, Q::total, 0};
      else if (qn == "external_work") c = {-1, Q::work, 0};
      else
        throw std::runtime_error(where + "/quantities: \"" + qn + "\" is not available in this formulation");
      if (c.comp < 0) throw std::runtime_error(where + "/quantities: unknown component in \"" + qn + "\"");
      if (c.particle < 0 && c.q < Q::kinetic)
        throw std::runtime_error(where + ": \"" + qn + "\" needs \"at\" or \"particle\"");
      c.water = water && c.particle >= 0;
      if (c.water) water_found_.push_back({c.particle, particle});
      columns_.push_back(c);
      header << "," << mon.name << "." << qn;
    }
  }
  if (path.empty()) {
    // Another rank than 0 under mpirun: it computes its share of each row; rank 0 writes the file.
  } else if (resume_bytes) {
    out_ = files::CheckedFile(path, *resume_bytes);  // the rows up to the checkpoint, then this run's
  } else {
    out_ = files::CheckedFile(path);
    out_.write(header_comment + "\n" + header.str() + "\n");
  }
  row_ << std::setprecision(10);
}

template <int Dim>
void Monitors<Dim>::record(const State<Dim>& st, const Formulation<Dim>& f, double external_work) {
  const auto& ps = st.solid;
  // Each column's value on this rank. Under mpirun a followed particle lives on one rank (the
  // others add -0), energies are this rank's share, water levels this rank's highest point: the
  // sums and maxima over the ranks are the row.
  // The other ranks' part of a value one rank holds is -0, the identity of IEEE addition, so that
  // a -0 it holds (a zero stress in tension's sign) stays -0 in the sum, as one rank writes it.
  const double none = parallel::distributed() ? -0.0 : 0.0;
  values_.assign(columns_.size(), none);
  highest_.assign(columns_.size(), -std::numeric_limits<double>::infinity());
  double ke = -1.0, se = -1.0;
  for (std::size_t col = 0; col < columns_.size(); ++col) {
    const Column& c = columns_[col];
    double& val = values_[col];
    if (c.q == Q::level) {
      const Gauge& g = gauges_[static_cast<std::size_t>(c.comp)];
      if (g.grid) val = parallel::rank() == 0 ? f.grid_water_level(g.x, g.z) : none;
      else if (const double top = water_level(st.fluid, g); std::isfinite(top)) highest_[col] = top;
      else if (!parallel::distributed()) highest_[col] = top;  // NaN: no liquid point near the line
      continue;
    }
    if (c.q == Q::probe) {  // the grid's fluid at a fixed point (the last completed step's nodes)
      val = parallel::rank() == 0 ? f.grid_value(probes_[static_cast<std::size_t>(c.comp)], c.grid) : none;
      continue;
    }
    if (c.water) {  // a water point: its own position, velocity, pore pressure and porosity
      const auto& ws = st.fluid;
      const int p = water_index(ws, c.particle);
      if (p < 0) val = parallel::distributed() ? none : std::numeric_limits<double>::quiet_NaN();  // it left the run (solver.escaped_water)
      else if (c.q == Q::disp) val = ws.x[p][c.comp] - ws.x0[p][c.comp];
      else if (c.q == Q::vel) val = ws.v[p][c.comp];
      else if (c.q == Q::pore) val = ws.p[p];
      else val = ws.n[p];
      continue;
    }
    const int p = c.particle < 0 ? -1 : st.index_of_id[c.particle];
    if (p < 0 && c.q < Q::kinetic) continue;  // held by another rank
    switch (c.q) {
      case Q::disp: val = ps.x[p][c.comp] - ps.x0[p][c.comp]; break;
      case Q::vel: val = ps.v[p][c.comp]; break;
      case Q::vel_fluid: val = ps.v_f[p][c.comp]; break;
      case Q::pore: val = ps.p[p]; break;
      case Q::porosity: val = ps.n[p]; break;
      case Q::stress: val = ps.sigma[p][c.comp]; break;
      case Q::p_mean: val = mean_stress(ps.sigma[p]); break;
      case Q::q_dev: val = deviatoric_stress(ps.sigma[p]); break;
      case Q::eps_p: val = ps.eps_p[p]; break;
      case Q::kinetic: val = ke = ke < 0 ? f.kinetic_energy(st) : ke; break;
      case Q::strain: val = se = se < 0 ? f.strain_energy(st) : se; break;
      case Q::total:
        ke = ke < 0 ? f.kinetic_energy(st) : ke;
        se = se < 0 ? f.strain_energy(st) : se;
        val = ke + se;
        break;
      case Q::work: val = parallel::rank() == 0 ? external_work : none; break;
      case Q::level:
      case Q::probe: break;  // above
    }
  }
  parallel::sum(std::span<double>(values_));
  parallel::max(std::span<double>(highest_));
  if (parallel::rank() != 0) return;
  row_.str("");
  row_ << st.time;
  for (std::size_t col = 0; col < columns_.size(); ++col) {
    const Column& c = columns_[col];
    const bool point_level = c.q == Q::level && !gauges_[static_cast<std::size_t>(c.comp)].grid;
    if (!point_level) row_ << "," << values_[col];
    else row_ << "," << (std::isinf(highest_[col]) ? std::numeric_limits<double>::quiet_NaN() : highest_[col]);
  }
  row_ << "\n";
  out_.write(row_.str());  // checked: a failed write throws files::WriteError
}

template <int Dim>
double Monitors<Dim>::water_level(const ParticleSet<Dim>& ws, const Gauge& g) const {
  double top = -std::numeric_limits<double>::infinity();  // m
  for (std::size_t p = 0; p < ws.size(); ++p) {
    if (std::abs(ws.x[p][0] - g.x) > reach_) continue;
    if constexpr (Dim == 3) {
      if (std::abs(ws.x[p][2] - g.z) > reach_) continue;
    }
    top = std::max(top, ws.x[p][1] + ws.l[p][1]);  // the top of the point's domain
  }
  return std::isfinite(top) ? top : std::numeric_limits<double>::quiet_NaN();
}

template <int Dim>
int Monitors<Dim>::water_index(const ParticleSet<Dim>& ws, std::int64_t id) {
  for (auto& [wid, index] : water_found_) {
    if (wid != id) continue;
    if (index < 0 || index >= static_cast<int>(ws.size()) || ws.id[index] != id) {
      index = -1;
      for (std::size_t p = 0; p < ws.size(); ++p)
        if (ws.id[p] == id) {
          index = static_cast<int>(p);
          break;
        }
    }
    return index;
  }
  return -1;
}

template <int Dim>
std::vector<std::string> Monitors<Dim>::describe() const {
  std::vector<std::string> lines;
  for (std::size_t k = 0; k < names_.size(); ++k) {
    const bool water = monitor_water_[k];
    std::ostringstream os;
    os << "monitor " << names_[k] << ": ";
    if (const int gi = monitor_gauge_[k]; gi >= 0) {
      const Gauge& g = gauges_[static_cast<std::size_t>(gi)];
      os << "water level on the vertical line x = " << g.x;
      if (Dim == 3) os << ", z = " << g.z;
      if (g.grid) os << " (the highest height where the grid's phase field phi crosses 1/2)";
      else os << " (the liquid points within " << reach_ << " m of it)";
    } else if (const int pi = monitor_probe_[k]; pi >= 0) {
      const auto& x = probes_[static_cast<std::size_t>(pi)];
      os << "fixed point (";
      for (int a = 0; a < Dim; ++a) os << (a ? ", " : "") << x[a];
      os << ") of the grid's fluid (Eulerian probe: ";
      const auto& reads = probe_reads_[static_cast<std::size_t>(pi)];
      for (std::size_t q = 0; q < reads.size(); ++q)
        os << (q ? ", " : "") << (reads[q] == "pore_pressure" ? "pore_pressure = the fluid's pressure" : reads[q]);
      os << " interpolated from the nodes)";
    } else if (monitor_particle_[k] < 0) os << "whole system";
    else {
      os << "follows " << (water ? "water point " : "solid particle ") << monitor_particle_[k] << " starting at (";
      for (int a = 0; a < Dim; ++a) os << (a ? ", " : "") << monitor_x0_[k][static_cast<std::size_t>(a)];
      os << ")";
    }
    lines.push_back(os.str());
  }
  return lines;
}

template class Monitors<2>;
template class Monitors<3>;

}  // namespace swmpm
