// Stage 3: histories, profiles, comparisons, plots and reports from a run directory.
#pragma once

#include <string>
#include <vector>

namespace swmpm::post {

/// Draws every monitor of RUN_DIR/monitors.csv into RUN_DIR/plots/<monitor>.png (one panel per
/// quantity, gnuplot pngcairo). Returns the files written.
std::vector<std::string> plot_monitors(const std::string& run_dir);

/// Reads a wide CSV (comment lines starting with '#' skipped): header names and columns.
struct Table {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
  const std::vector<double>& column(const std::string& name) const;
};
Table read_csv(const std::string& path);

}  // namespace swmpm::post
