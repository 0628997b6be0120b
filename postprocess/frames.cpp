// The VTU series of a run (results.pvd), the quantities a frame offers, and sampling a frame at
// a point: the nearest particle, or a kernel average of the particles around it.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "postprocess/postprocess.hpp"
#include "scene/input.hpp"

namespace fs = std::filesystem;

namespace swmpm::post {

namespace {

constexpr const char* vector_components[] = {"x", "y", "z"};
// Voigt order of the 6-component arrays (docs/architecture.md, Notation).
constexpr const char* tensor_components[] = {"xx", "yy", "zz", "xy", "yz", "xz"};

int tensor_component(const std::string& s) {
  for (int k = 0; k < 6; ++k)
    if (s == tensor_components[k]) return k;
  if (s == "yx") return 3;  // symmetric: either order
  if (s == "zy") return 4;
  if (s == "zx") return 5;
  return -2;
}

int vector_component(const std::string& s) {
  if (s == "magnitude") return -1;
  for (int k = 0; k < 3; ++k)
    if (s == vector_components[k]) return k;
  return -2;
}

/// The scene's dimension from RUN_DIR/scene.json; 0 when it cannot be read.
int scene_dimension(const fs::path& run_dir) {
  try {
    return scene::read_json_file((run_dir / "scene.json").string(), "scene file").value("dimension", 0);
  } catch (const std::exception&) {
    return 0;
  }
}

}  // namespace

RunSeries::RunSeries(const std::string& run_dir, const std::string& phase) : run_dir_(run_dir), phase_(phase) {
  const fs::path dir(run_dir);
  if (!fs::is_directory(dir)) throw std::runtime_error(run_dir + ": not a run directory (no such directory)");
  if (phase != "solid" && phase != "fluid" && phase != "grid")
    throw std::runtime_error("--phase \"" + phase + "\": expected solid, fluid or grid");
  const fs::path pvd = dir / "output" / "results.pvd";
  if (!fs::exists(pvd))
    throw std::runtime_error(pvd.string() + ": missing, the run has no frames (run `swmpm solve " + run_dir +
                             "` first)");
  const auto entries = scene::read_pvd(pvd.string());
  std::vector<std::string> groups;
  auto collect = [&](const std::string& group) {
    for (const auto& e : entries)
      if (e.group == group) frames_.push_back({e.time, (pvd.parent_path() / e.file).string()});
  };
  for (const auto& e : entries)
    if (std::find(groups.begin(), groups.end(), e.group) == groups.end()) groups.push_back(e.group);
  collect(phase);
  if (frames_.empty() && phase == "fluid") {
    // Single-point formulations write one particle set that carries both phases.
    collect("solid");
    fluid_on_solid_ = !frames_.empty() && load(0).find("fluid_velocity") != nullptr;
    if (!fluid_on_solid_) frames_.clear();
  }
  if (frames_.empty()) {
    std::string list;
    for (const auto& g : groups) list += (list.empty() ? "" : ", ") + g;
    throw std::runtime_error(pvd.string() + ": no " + phase + " frames (phases in the series: " +
                             (list.empty() ? "none" : list) + ")");
  }
  std::stable_sort(frames_.begin(), frames_.end(), [](const Frame& a, const Frame& b) { return a.time < b.time; });
  dimension_ = scene_dimension(dir);
  if (dimension_ != 2 && dimension_ != 3) {
    // No readable scene.json: 3D when any particle of the first frame is off the z = 0 plane.
    const auto first = load(0);
    dimension_ = std::any_of(first.points.begin(), first.points.end(), [](const auto& x) { return x[2] != 0.0; })
                     ? 3
                     : 2;
  }
}

std::size_t RunSeries::nearest_frame(double t) const {
  std::size_t best = 0;
  for (std::size_t k = 1; k < frames_.size(); ++k)
    if (std::abs(frames_[k].time - t) < std::abs(frames_[best].time - t)) best = k;
  return best;
}

scene::PointCloud RunSeries::load(std::size_t k) const { return scene::read_vtu(frames_.at(k).path); }

Quantity::Quantity(const scene::PointCloud& frame, const std::string& name, bool fluid_fields) : name_(name) {
  std::string array = name, part;
  const auto cut = name.rfind('_');
  if (const auto* a = frame.find(name); a != nullptr && a->components == 1) {
    array_ = a;
    return;
  }
  if (cut != std::string::npos) {
    array = name.substr(0, cut);
    part = name.substr(cut + 1);
    if (fluid_fields && array == "velocity") array = "fluid_velocity";
    if (const auto* a = frame.find(array)) {
      const int c = a->components == 3 ? vector_component(part) : a->components == 6 ? tensor_component(part) : -2;
      if (c >= -1) {
        array_ = a;
        component_ = c;
        return;
      }
    }
  }
  std::string list;
  for (const auto& q : available_quantities(frame, fluid_fields)) list += (list.empty() ? "" : ", ") + q;
  throw std::runtime_error("unknown quantity \"" + name + "\" (available: " + list + ")");
}

double Quantity::operator()(std::size_t p) const {
  const auto nc = static_cast<std::size_t>(array_->components);
  const double* v = array_->values.data() + p * nc;
  if (component_ >= 0) return v[component_];
  double s = 0.0;
  for (std::size_t c = 0; c < nc; ++c) s += v[c] * v[c];
  return std::sqrt(s);
}

std::vector<std::string> available_quantities(const scene::PointCloud& frame, bool fluid_fields) {
  std::vector<std::string> names;
  for (const auto& a : frame.arrays) {
    std::string base = a.name;
    if (fluid_fields && base == "fluid_velocity") base = "velocity";
    else if (fluid_fields && base == "velocity") continue;  // the solid's velocity is not the fluid's
    if (a.components == 1) names.push_back(base);
    else if (a.components == 3) {
      for (const char* c : vector_components) names.push_back(base + "_" + c);
      names.push_back(base + "_magnitude");
    } else if (a.components == 6) {
      for (const char* c : tensor_components) names.push_back(base + "_" + c);
    }
  }
  return names;
}

double particle_spacing(const scene::PointCloud& frame, int dimension) {
  double h = 0.0;
  if (const auto* half = frame.find("half_size"); half != nullptr && half->components == 3) {
    for (double l : half->values) h = std::max(h, 2.0 * l);
  } else if (const auto* volume = frame.find("volume")) {
    for (double v : volume->values) h = std::max(h, std::pow(v, 1.0 / dimension));
  } else {
    // A grid frame (mpm-fem's nodes): the largest gap between neighbouring node columns, the cell
    // size (B-spline nodes sit at the Greville abscissae: h/2 apart at the ends, h inside).
    std::vector<double> xs;
    for (const auto& x : frame.points) xs.push_back(x[0]);
    std::sort(xs.begin(), xs.end());
    xs.erase(std::unique(xs.begin(), xs.end(), [](double a, double b) { return std::abs(a - b) < 1e-12; }), xs.end());
    for (std::size_t k = 1; k < xs.size(); ++k) h = std::max(h, xs[k] - xs[k - 1]);
  }
  if (!(h > 0.0))
    throw std::runtime_error("the frames have neither half_size nor volume to tell the particle spacing: give --radius");
  return h;
}

std::pair<std::size_t, double> nearest_particle(const scene::PointCloud& frame, const Point& x) {
  std::size_t best = frame.size();
  double best_d2 = std::numeric_limits<double>::infinity();
  for (std::size_t p = 0; p < frame.size(); ++p) {
    const auto& y = frame.points[p];
    const double d2 = (y[0] - x[0]) * (y[0] - x[0]) + (y[1] - x[1]) * (y[1] - x[1]) + (y[2] - x[2]) * (y[2] - x[2]);
    if (d2 < best_d2) {  // strict: on a tie the first particle in the file wins, as for monitors
      best_d2 = d2;
      best = p;
    }
  }
  return {best, std::sqrt(best_d2)};
}

double kernel_average(const scene::PointCloud& frame, const Quantity& q, const Point& x, double radius) {
  // Weight (1 − (r/R)²)²: smooth, with zero value and slope at r = R, so a particle crossing the
  // radius between frames does not make the history jump.
  const double R2 = radius * radius;
  double sum_w = 0.0, sum_wv = 0.0;
  for (std::size_t p = 0; p < frame.size(); ++p) {
    const auto& y = frame.points[p];
    const double d2 = (y[0] - x[0]) * (y[0] - x[0]) + (y[1] - x[1]) * (y[1] - x[1]) + (y[2] - x[2]) * (y[2] - x[2]);
    if (d2 >= R2) continue;
    const double w = (1.0 - d2 / R2) * (1.0 - d2 / R2);
    sum_w += w;
    sum_wv += w * q(p);
  }
  return sum_w > 0.0 ? sum_wv / sum_w : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace swmpm::post
