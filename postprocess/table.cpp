// CSV in and out: monitors.csv, reference curves, history/profile results.
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "postprocess/postprocess.hpp"
#include "scene/input.hpp"

namespace swmpm::post {

namespace {

std::vector<std::string> split_line(std::string line) {
  if (!line.empty() && line.back() == '\r') line.pop_back();  // files saved on Windows
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

/// A cell as a number; an empty cell is NaN (an empty value in our own CSVs).
bool parse_number(const std::string& cell, double& value) {
  const std::string s = trim(cell);
  if (s.empty()) {
    value = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  std::size_t used = 0;
  try {
    value = std::stod(s, &used);
  } catch (const std::exception&) {
    return false;
  }
  return used == s.size();
}

bool all_numbers(const std::vector<std::string>& cells) {
  double v;
  for (const auto& c : cells)
    if (trim(c).empty() || !parse_number(c, v)) return false;
  return !cells.empty();
}

}  // namespace

const std::vector<double>& Table::column(const std::string& name) const {
  for (std::size_t k = 0; k < names.size(); ++k)
    if (names[k] == name) return columns[k];
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  throw std::runtime_error("no column \"" + name + "\" (columns: " + list + ")");
}

bool Table::has(const std::string& name) const {
  for (const auto& n : names)
    if (n == name) return true;
  return false;
}

namespace {

/// Calls fn(cells, line_no) for every line of the CSV file that is not empty or a # comment. Only
/// a regular file of at most scene::kMaxInputBytes is read (a FIFO blocked, /dev/zero grew memory).
template <class Fn>
void for_each_csv_line(const std::string& path, const std::string& what, Fn&& fn) {
  std::istringstream in(scene::read_input_file(path, what));
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#' || line == "\r") continue;
    fn(split_line(line), line_no);
  }
}

/// The numbers of a data row; throws naming the file, line and cell that is not a number.
std::vector<double> parse_row(const std::vector<std::string>& cells, const std::string& path, std::size_t line_no) {
  std::vector<double> row(cells.size());
  for (std::size_t k = 0; k < cells.size(); ++k)
    if (!parse_number(cells[k], row[k]))
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": \"" + cells[k] + "\" is not a number");
  return row;
}

}  // namespace

Table read_csv(const std::string& path) {
  Table t;
  for_each_csv_line(path, "CSV file", [&](const std::vector<std::string>& cells, std::size_t line_no) {
    if (t.names.empty()) {
      for (const auto& c : cells) t.names.push_back(trim(c));
      t.columns.resize(t.names.size());
      return;
    }
    if (cells.size() != t.names.size())
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": " + std::to_string(cells.size()) +
                               " values where the header has " + std::to_string(t.names.size()));
    const auto row = parse_row(cells, path, line_no);
    for (std::size_t k = 0; k < row.size(); ++k) t.columns[k].push_back(row[k]);
  });
  if (t.names.empty()) throw std::runtime_error(path + ": no header line");
  return t;
}

Curve read_reference(const std::string& path, const std::string& column) {
  std::vector<std::string> names;
  std::vector<std::vector<double>> rows;
  for_each_csv_line(path, "reference file", [&](const std::vector<std::string>& cells, std::size_t line_no) {
    // A header is optional: a first line that is all numbers is data.
    if (names.empty() && rows.empty() && !all_numbers(cells)) {
      for (const auto& c : cells) names.push_back(trim(c));
      return;
    }
    rows.push_back(parse_row(cells, path, line_no));
  });
  if (rows.empty()) throw std::runtime_error(path + ": no data rows in the reference file");
  std::size_t k = 1;
  Curve c;
  c.name = names.size() > 1 ? names[1] : "column 2";
  if (!column.empty()) {
    std::size_t found = names.size();
    for (std::size_t j = 0; j < names.size(); ++j)
      if (names[j] == column) found = j;
    if (found == names.size()) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      throw std::runtime_error(path + ": no column \"" + column + "\" (columns: " +
                               (list.empty() ? "none, the file has no header line" : list) + ")");
    }
    k = found;
    c.name = column;
  }
  for (const auto& row : rows) {
    if (row.size() <= k || row.empty())
      throw std::runtime_error(path + ": a row has fewer than " + std::to_string(k + 1) + " values");
    if (std::isnan(row[0]) || std::isnan(row[k])) continue;  // empty cells: no point
    c.t.push_back(row[0]);
    c.v.push_back(row[k]);
  }
  return c;
}

void write_csv(const CsvResult& result, std::ostream& out) {
  for (const auto& c : result.comments) out << "# " << c << "\n";
  for (std::size_t k = 0; k < result.names.size(); ++k) out << (k ? "," : "") << result.names[k];
  out << "\n" << std::setprecision(10);
  for (const auto& row : result.rows) {
    for (std::size_t k = 0; k < row.size(); ++k) {
      if (k) out << ",";
      if (!std::isnan(row[k])) out << row[k];  // NaN: no particle there, an empty cell
    }
    out << "\n";
  }
}

std::string unit_of(const std::string& q, int dimension) {
  // 2D is plane strain: extensive quantities are per metre of thickness.
  const std::string per_m = dimension == 2 ? "/m" : "";
  auto starts = [&q](const char* prefix) { return q.rfind(prefix, 0) == 0; };
  if (q == "time") return "s";
  if (starts("fluid_velocity") || starts("velocity")) return "m/s";
  if (starts("displacement") || starts("half_size") || q == "water_level") return "m";
  if (starts("stress") || q == "mean_effective_stress" || q == "deviatoric_stress" || q == "pore_pressure")
    return "Pa";
  if (q == "mass" || q == "fluid_mass") return "kg" + per_m;
  if (q == "volume") return "m^3" + per_m;
  if (q == "plastic_strain" || q == "volume_ratio" || q == "porosity") return "-";
  if (q == "kinetic_energy" || q == "strain_energy" || q == "total_energy" || q == "external_work") return "J" + per_m;
  return "";
}

}  // namespace swmpm::post
