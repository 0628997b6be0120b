// Stage 3: histories, profiles, comparisons, plots and reports from a run directory.
//
// Everything here reads files only: RUN_DIR/monitors.csv, run.json, scene.json and the VTU series
// output/results.pvd (through scene::read_pvd / read_vtu, i.e. VTK). Errors are std::runtime_error
// with one line that names the file or option, what is wrong and what is allowed.
#pragma once

#include <array>
#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

#include "scene/pointcloud.hpp"

namespace swmpm::post {

// ---------------------------------------------------------------------------------------------
// Tables (table.cpp)

/// Reads a wide CSV (comment lines starting with '#' skipped): header names and columns.
struct Table {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
  const std::vector<double>& column(const std::string& name) const;
  bool has(const std::string& name) const;
};
Table read_csv(const std::string& path);

/// A curve v(t) from a reference CSV: the first column is the abscissa (time), the value is the
/// column named `column`, or the second column when `column` is empty. '#' lines are skipped;
/// a header line is optional (a first line of numbers is data).
struct Curve {
  std::string name;  // the value column's header (or "column 2")
  std::vector<double> t, v;
};
Curve read_reference(const std::string& path, const std::string& column = "");

/// A result to be written as CSV: '#' comment lines, a header, rows (NaN = empty cell).
struct CsvResult {
  std::vector<std::string> comments;
  std::vector<std::string> names;
  std::vector<std::vector<double>> rows;
};
void write_csv(const CsvResult& result, std::ostream& out);

/// Physical unit of a quantity name ("m", "Pa", "m/s", "-", "" when unknown), for axis labels;
/// in 2D (plane strain) extensive quantities are per metre ("J/m").
std::string unit_of(const std::string& quantity, int dimension = 3);

// ---------------------------------------------------------------------------------------------
// Options as typed on the command line (options.cpp)

using Point = std::array<double, 3>;  // m; z = 0 in 2D
/// "X,Y" or "X,Y,Z" (numbers in m); `option` names the option in the error message.
/// Returns the point and, in `given`, how many coordinates were written (2 or 3).
Point parse_point(const std::string& text, const std::string& option, int* given = nullptr);
/// "t1,t2,..." (s).
std::vector<double> parse_times(const std::string& text, const std::string& option);
/// "NAME.QUANTITY=FILE.csv" of --reference.
struct ReferenceSpec {
  std::string column;  // monitors.csv column, "<monitor>.<quantity>"
  std::string path;    // reference CSV
};
ReferenceSpec parse_reference_spec(const std::string& text);

enum class Method { nearest, interpolate };
Method parse_method(const std::string& text);

// ---------------------------------------------------------------------------------------------
// The VTU series of one phase and the quantities in a frame (frames.cpp)

struct Frame {
  double time;       // s
  std::string path;  // the .vtu file
};

/// The frames of one phase of RUN_DIR/output/results.pvd, in time order.
class RunSeries {
 public:
  /// Throws when RUN_DIR or results.pvd is missing or holds no frame of that phase.
  RunSeries(const std::string& run_dir, const std::string& phase);
  const std::string& run_dir() const { return run_dir_; }
  const std::string& phase() const { return phase_; }
  const std::vector<Frame>& frames() const { return frames_; }
  /// Index of the frame whose time is nearest t.
  std::size_t nearest_frame(double t) const;
  scene::PointCloud load(std::size_t k) const;
  /// 2 or 3: the run's scene.json "dimension" (or 2 when the frames have no z extent).
  int dimension() const { return dimension_; }
  /// Single-point two-phase runs keep the fluid on the solid particles: phase "fluid" then reads
  /// the solid frames and maps velocity_* to the fluid_velocity array.
  bool fluid_on_solid_frames() const { return fluid_on_solid_; }

 private:
  std::string run_dir_, phase_;
  std::vector<Frame> frames_;
  int dimension_ = 2;
  bool fluid_on_solid_ = false;
};

/// How to read one quantity of a frame: a scalar array, one component of a vector
/// (displacement_x|y|z, velocity_x|y|z, <array>_magnitude) or of a symmetric tensor
/// (stress_xx|yy|zz|xy|yz|xz, Voigt order as stored).
class Quantity {
 public:
  /// Throws "unknown quantity ... (available: ...)" when the frame has no such array.
  Quantity(const scene::PointCloud& frame, const std::string& name, bool fluid_fields = false);
  double operator()(std::size_t p) const;
  const std::string& name() const { return name_; }

 private:
  std::string name_;
  const scene::PointArray* array_ = nullptr;
  int component_ = 0;  // -1: Euclidean norm of the vector
};
/// Every quantity name a frame offers (scalars, vector and tensor components, magnitudes).
std::vector<std::string> available_quantities(const scene::PointCloud& frame, bool fluid_fields = false);

/// Particle spacing of a frame [m]: 2 × the largest half_size component (from volume when the
/// frame has no half_size). The default sampling radius is 1.5 × this.
double particle_spacing(const scene::PointCloud& frame, int dimension);

/// Index of the particle nearest x and its distance [m] (index = frame.size() when empty).
std::pair<std::size_t, double> nearest_particle(const scene::PointCloud& frame, const Point& x);
/// Kernel average of q over the particles within `radius` of x, weight (1 − (r/R)²)²;
/// NaN when no particle is that close.
double kernel_average(const scene::PointCloud& frame, const Quantity& q, const Point& x, double radius);

// ---------------------------------------------------------------------------------------------
// history and profile (history.cpp)

struct HistoryOptions {
  Point point{0, 0, 0};
  int point_coordinates = 2;  // as typed: 2 or 3 (checked against the run's dimension)
  std::string phase = "solid";
  std::string quantity;
  Method method = Method::nearest;
  double radius = 0.0;  // m; 0: 1.5 × particle spacing
};
/// Columns time, <quantity>: one row per frame of the phase.
CsvResult history(const std::string& run_dir, const HistoryOptions& o);

struct ProfileOptions {
  Point from{0, 0, 0}, to{0, 0, 0};
  int point_coordinates = 2;
  double time = 0.0;  // s; the frame nearest this time is used
  std::string phase = "solid";
  std::string quantity;
  int points = 50;
  Method method = Method::nearest;
  double radius = 0.0;
};
/// Columns s, x, y[, z], <quantity>; `frame_note` receives which frame was used.
CsvResult profile(const std::string& run_dir, const ProfileOptions& o, std::string* frame_note = nullptr);

/// Every particle of the frame nearest `time` (phase solid or fluid), read through VTK: columns
/// x, y[, z], then every array of the frame, vectors as NAME_x, NAME_y[, NAME_z] (2D frames drop
/// the z component), symmetric tensors as NAME_xx, NAME_yy, NAME_zz, NAME_xy, NAME_yz, NAME_xz.
/// For scripts that want whole fields (bench/speed_vs_error.py) without parsing VTU themselves.
CsvResult frame_table(const std::string& run_dir, double time, const std::string& phase,
                      std::string* frame_note = nullptr);

// ---------------------------------------------------------------------------------------------
// compare (compare.cpp)

struct Comparison {
  std::string monitor, reference;  // monitors.csv column, reference file
  std::size_t points = 0;          // reference points inside the run's time span
  double t_first = 0, t_last = 0;  // s, the compared span
  double rel_l2 = 0;               // ‖a − r‖₂ / ‖r‖₂ over the compared points
  double max_abs = 0, max_abs_time = 0;
  double peak_run = 0, peak_run_time = 0;  // largest |value| of the run in the span (signed)
  double peak_ref = 0, peak_ref_time = 0;
};
/// The run's monitor column, interpolated linearly onto the reference times that fall inside the
/// run's time span, against the reference values.
Comparison compare(const std::string& run_dir, const std::string& monitor, const std::string& reference_path,
                   const std::string& reference_column = "");
/// Several lines of text, for the terminal.
std::string describe(const Comparison& c);

// ---------------------------------------------------------------------------------------------
// plots (plot.cpp): gnuplot, pngcairo

/// The single-element curves of `swmpm element` (a table with columns axial_strain, p, q,
/// volumetric_strain; Pa, compression positive) in one PNG: q–p′, q–ε_a and ε_v–ε_a, the last
/// replaced by u–ε_a when the table has excess_pore_pressure, plus ψ–ε_a when it has
/// state_parameter. With a p0 column, one curve per p0 (rows of one run consecutive).
void plot_element_curves(const CsvResult& table, const std::string& title, const std::string& png);

/// Draws every monitor of RUN_DIR/monitors.csv into RUN_DIR/plots/<monitor>.png (one panel per
/// quantity); a reference curve is overlaid on the panel its spec names. Returns the files written.
std::vector<std::string> plot_monitors(const std::string& run_dir, const std::vector<ReferenceSpec>& references = {});
/// One PNG per time, RUN_DIR/plots/field_<quantity>_<t>.png: the particles of the frame nearest
/// t coloured by the quantity, equal axis scales, a colour bar (3D: the slab around mid-z).
std::vector<std::string> plot_fields(const std::string& run_dir, const std::string& quantity,
                                     const std::vector<double>& times, const std::string& phase = "solid");

/// One curve of a log-log chart; `dashed` for a series that is only indicative.
struct ChartSeries {
  std::string title;
  std::vector<double> x, y;
  bool dashed = false;
  int colour = -1;  // index into the palette (-1: the series' own index)
  int point = -1;   // gnuplot point type (-1: by the series' index)
};
struct ChartLabels {
  std::string title, x, y;
  double y_line = 0.0;       // a horizontal line at this y (a tolerance); 0: none
  std::string y_line_title;  // its label
};
/// A log-log chart of the series (points with x or y not positive are left out) into `png`,
/// replaced atomically (the caller claims it on its folder's ledger first).
void plot_loglog(const std::vector<ChartSeries>& series, const ChartLabels& labels, const std::string& png);

// ---------------------------------------------------------------------------------------------
// report (report.cpp)

/// Writes RUN_DIR/report.md (setup, cost, comparisons, plots; missing plots are drawn first).
std::string write_report(const std::string& run_dir, const std::vector<ReferenceSpec>& references = {});

}  // namespace swmpm::post
