#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "postprocess/postprocess.hpp"

namespace fs = std::filesystem;

namespace swmpm::post {

const std::vector<double>& Table::column(const std::string& name) const {
  for (std::size_t k = 0; k < names.size(); ++k)
    if (names[k] == name) return columns[k];
  throw std::runtime_error("no column \"" + name + "\"");
}

Table read_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open file");
  Table t;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string cell;
    if (t.names.empty()) {
      while (std::getline(ss, cell, ',')) t.names.push_back(cell);
      t.columns.resize(t.names.size());
      continue;
    }
    std::size_t k = 0;
    while (std::getline(ss, cell, ',') && k < t.columns.size()) t.columns[k++].push_back(std::stod(cell));
    if (k != t.names.size()) throw std::runtime_error(path + ": ragged row: " + line);
  }
  if (t.names.empty()) throw std::runtime_error(path + ": no header line");
  return t;
}

std::vector<std::string> plot_monitors(const std::string& run_dir) {
  const fs::path dir(run_dir);
  const fs::path csv = dir / "monitors.csv";
  const Table t = read_csv(csv.string());
  // Group columns "<monitor>.<quantity>" by monitor.
  std::map<std::string, std::vector<std::size_t>> groups;
  for (std::size_t k = 1; k < t.names.size(); ++k)
    groups[t.names[k].substr(0, t.names[k].find('.'))].push_back(k);
  fs::create_directories(dir / "plots");
  std::vector<std::string> written;
  for (const auto& [monitor, cols] : groups) {
    const fs::path png = dir / "plots" / (monitor + ".png");
    const int rows = static_cast<int>(cols.size());
    std::ostringstream gp;
    gp << "set terminal pngcairo size 900," << 260 * rows + 60 << " font 'Sans,10'\n"
       << "set output '" << png.string() << "'\n"
       << "set datafile separator ','\nset datafile commentschars '#'\nset key autotitle columnhead\n"
       << "set grid\nset multiplot layout " << rows << ",1 title 'monitor " << monitor << "'\n";
    for (std::size_t c : cols) {
      gp << "set xlabel 'time [s]'\nset ylabel '" << t.names[c].substr(monitor.size() + 1) << "' noenhanced\n"
         << "plot '" << csv.string() << "' using 1:" << c + 1 << " with lines lw 2 title '" << t.names[c]
         << "' noenhanced\n";
    }
    gp << "unset multiplot\n";
    FILE* pipe = popen("gnuplot 2>&1", "w");
    if (pipe == nullptr) throw std::runtime_error("cannot start gnuplot (apt-get install gnuplot-nox)");
    std::fputs(gp.str().c_str(), pipe);
    const int rc = pclose(pipe);
    if (rc != 0 || !fs::exists(png))
      throw std::runtime_error("gnuplot failed to draw " + png.string() + " (apt-get install gnuplot-nox)");
    written.push_back(png.string());
  }
  return written;
}

}  // namespace swmpm::post
