// history: a quantity at a point through every frame; profile: a quantity along a segment in one
// frame. Both read the VTU series, so they work for any point and any saved frame, unlike
// monitors.csv, which holds only what the scene asked for before the run.
#include <cmath>
#include <limits>
#include <stdexcept>

#include "postprocess/format.hpp"
#include "postprocess/postprocess.hpp"

namespace swmpm::post {

namespace {

constexpr double radius_in_spacings = 1.5;

/// A 2D run takes X,Y (or X,Y,0); a 3D run needs X,Y,Z.
void check_coordinates(const std::string& option, int given, const Point& x, int dimension) {
  if (dimension == 3 && given < 3)
    throw std::runtime_error(option + ": the run is 3D, give X,Y,Z");
  if (dimension == 2 && given == 3 && x[2] != 0.0)
    throw std::runtime_error(option + ": the run is 2D (plane x-y), give X,Y");
}

/// The sampling radius [m] and a sentence that says where it came from.
std::pair<double, std::string> sampling_radius(double requested, const scene::PointCloud& frame, int dimension) {
  if (requested > 0.0) return {requested, "R = " + num(requested) + " m (--radius)"};
  const double h = particle_spacing(frame, dimension);
  const double R = radius_in_spacings * h;
  return {R, "R = " + num(R) + " m (1.5 x the particle spacing " + num(h) + " m)"};
}

std::string quantity_text(const std::string& q, int dimension) {
  const std::string u = unit_of(q, dimension);
  return q + (u.empty() ? "" : " [" + u + "]");
}

[[noreturn]] void outside(const Point& x, int dimension, const RunSeries& s, double distance, double R, double t) {
  throw std::runtime_error("point " + point_text(x, dimension) + " is outside all " + s.phase() +
                           " particles: the nearest is " + num(distance) + " m away at t = " + num(t) +
                           " s, more than the sampling radius " + num(R) + " m");
}

/// Index of the particle with that id in a frame, or frame.size().
std::size_t index_of_id(const scene::PointCloud& frame, double id) {
  const auto& ids = frame.get("id", "frame").values;
  for (std::size_t p = 0; p < ids.size(); ++p)
    if (ids[p] == id) return p;
  return frame.size();
}

}  // namespace

CsvResult history(const std::string& run_dir, const HistoryOptions& o) {
  const RunSeries series(run_dir, o.phase);
  const int dim = series.dimension();
  check_coordinates("--point", o.point_coordinates, o.point, dim);
  const bool fluid = series.fluid_on_solid_frames();
  const auto first = series.load(0);
  const Quantity check(first, o.quantity, fluid);  // an unknown name fails before other frames are read
  (void)check;
  const auto [R, radius_note] = sampling_radius(o.radius, first, dim);
  const double nan = std::numeric_limits<double>::quiet_NaN();

  CsvResult r;
  r.names = {"time", o.quantity};
  r.comments.push_back("swmpm history: run " + run_dir + ", phase " + o.phase + ", quantity " +
                       quantity_text(o.quantity, dim) + " at " + point_text(o.point, dim) + ", " +
                       std::to_string(series.frames().size()) + " frames of output/results.pvd");
  if (o.method == Method::nearest) {
    const auto [p0, d] = nearest_particle(first, o.point);
    if (p0 == first.size() || d > R) outside(o.point, dim, series, d, R, series.frames()[0].time);
    const auto* ids = first.find("id");
    if (ids == nullptr)
      throw std::runtime_error(series.frames()[0].path + ": the frames have no id array, use --method interpolate");
    const double id = ids->values[p0];
    r.comments.push_back("method nearest: particle id " + num(id, 15) + ", the nearest to the point in the first frame (t = " +
                         num(series.frames()[0].time) + " s), at " + point_text(first.points[p0], dim) + ", " +
                         num(d) + " m away; followed by its id through all frames");
    for (std::size_t k = 0; k < series.frames().size(); ++k) {
      const auto frame = k == 0 ? first : series.load(k);
      const std::size_t p = index_of_id(frame, id);
      r.rows.push_back({series.frames()[k].time, p < frame.size() ? Quantity(frame, o.quantity, fluid)(p) : nan});
    }
  } else {
    r.comments.push_back("method interpolate: kernel average, weight (1 - (r/R)^2)^2, of the particles within " +
                         radius_note + " of the point, at their current positions in each frame; empty: none");
    for (std::size_t k = 0; k < series.frames().size(); ++k) {
      const auto frame = k == 0 ? first : series.load(k);
      const double v = kernel_average(frame, Quantity(frame, o.quantity, fluid), o.point, R);
      if (k == 0 && std::isnan(v)) outside(o.point, dim, series, nearest_particle(frame, o.point).second, R, series.frames()[0].time);
      r.rows.push_back({series.frames()[k].time, v});
    }
  }
  return r;
}

CsvResult profile(const std::string& run_dir, const ProfileOptions& o, std::string* frame_note) {
  if (o.points < 2) throw std::runtime_error("--points " + std::to_string(o.points) + ": expected at least 2");
  const RunSeries series(run_dir, o.phase);
  const int dim = series.dimension();
  check_coordinates("--from/--to", o.point_coordinates, o.from, dim);
  check_coordinates("--from/--to", o.point_coordinates, o.to, dim);
  const std::size_t k = series.nearest_frame(o.time);
  const Frame& f = series.frames()[k];
  const auto frame = series.load(k);
  const Quantity q(frame, o.quantity, series.fluid_on_solid_frames());
  const auto [R, radius_note] = sampling_radius(o.radius, frame, dim);
  const std::string note = "the frame at t = " + num(f.time) + " s, the nearest to --time " + num(o.time) + " (" +
                           f.path + ", frame " + std::to_string(k + 1) + " of " +
                           std::to_string(series.frames().size()) + ")";
  if (frame_note) *frame_note = note;

  CsvResult r;
  r.comments.push_back("swmpm profile: run " + run_dir + ", phase " + o.phase + ", quantity " +
                       quantity_text(o.quantity, dim) + " from " + point_text(o.from, dim) + " to " +
                       point_text(o.to, dim) + ", " + std::to_string(o.points) + " points");
  r.comments.push_back(note);
  r.comments.push_back(o.method == Method::nearest
                           ? "method nearest: the particle nearest each point (current positions), empty when none is within " + radius_note
                           : "method interpolate: kernel average, weight (1 - (r/R)^2)^2, of the particles within " + radius_note + "; empty: none");
  r.names = {"s", "x", "y"};
  if (dim == 3) r.names.push_back("z");
  r.names.push_back(o.quantity);
  double length2 = 0.0;
  for (int a = 0; a < 3; ++a) length2 += (o.to[a] - o.from[a]) * (o.to[a] - o.from[a]);
  const double length = std::sqrt(length2);
  bool any = false;
  for (int i = 0; i < o.points; ++i) {
    const double u = static_cast<double>(i) / (o.points - 1);
    Point x;
    for (int a = 0; a < 3; ++a) x[a] = o.from[a] + u * (o.to[a] - o.from[a]);
    double v = std::numeric_limits<double>::quiet_NaN();
    if (o.method == Method::nearest) {
      const auto [p, d] = nearest_particle(frame, x);
      if (p < frame.size() && d <= R) v = q(p);
    } else {
      v = kernel_average(frame, q, x, R);
    }
    any = any || !std::isnan(v);
    std::vector<double> row{u * length, x[0], x[1]};
    if (dim == 3) row.push_back(x[2]);
    row.push_back(v);
    r.rows.push_back(std::move(row));
  }
  if (!any)
    throw std::runtime_error("the segment " + point_text(o.from, dim) + " - " + point_text(o.to, dim) +
                             " is outside all " + o.phase + " particles at t = " + num(f.time) + " s (no particle within " +
                             num(R) + " m of any of its points)");
  return r;
}

CsvResult frame_table(const std::string& run_dir, double time, const std::string& phase, std::string* frame_note) {
  const RunSeries series(run_dir, phase);
  const int dim = series.dimension();
  const std::size_t k = series.nearest_frame(time);
  const Frame& f = series.frames()[k];
  const auto frame = series.load(k);
  const std::string note = "the frame at t = " + num(f.time) + " s, the nearest to --time " + num(time) + " (" + f.path +
                           ", frame " + std::to_string(k + 1) + " of " + std::to_string(series.frames().size()) + ")";
  if (frame_note) *frame_note = note;
  CsvResult r;
  r.comments.push_back("swmpm frame: run " + run_dir + ", phase " + phase + ", every particle");
  r.comments.push_back(note);
  static const char* axes[] = {"x", "y", "z"};
  static const char* voigt[] = {"xx", "yy", "zz", "xy", "yz", "xz"};
  for (int a = 0; a < dim; ++a) r.names.push_back(axes[a]);
  for (const auto& arr : frame.arrays) {
    if (arr.components == 1) r.names.push_back(arr.name);
    else if (arr.components == 3)
      for (int a = 0; a < dim; ++a) r.names.push_back(arr.name + "_" + axes[a]);
    else if (arr.components == 6)
      for (const char* c : voigt) r.names.push_back(arr.name + "_" + c);
    else
      for (int c = 0; c < arr.components; ++c) r.names.push_back(arr.name + "_" + std::to_string(c));
  }
  r.rows.reserve(frame.size());
  for (std::size_t p = 0; p < frame.size(); ++p) {
    std::vector<double> row;
    row.reserve(r.names.size());
    for (int a = 0; a < dim; ++a) row.push_back(frame.points[p][a]);
    for (const auto& arr : frame.arrays) {
      const int shown = arr.components == 3 ? dim : arr.components;
      for (int c = 0; c < shown; ++c) row.push_back(arr.values[p * static_cast<std::size_t>(arr.components) + c]);
    }
    r.rows.push_back(std::move(row));
  }
  return r;
}

}  // namespace swmpm::post
