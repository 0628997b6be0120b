// Command-line values of the postprocess commands, checked here so every command reports a bad
// value the same way: the option, what was typed, what is allowed.
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "postprocess/postprocess.hpp"

namespace swmpm::post {

namespace {

/// Comma-separated finite numbers; false on anything else.
bool parse_numbers(const std::string& text, std::vector<double>& out) {
  out.clear();
  std::stringstream ss(text);
  std::string cell;
  while (std::getline(ss, cell, ',')) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(cell, &used);
    } catch (const std::exception&) {
      return false;
    }
    if (cell.find_first_not_of(" \t", used) != std::string::npos || !std::isfinite(v)) return false;
    out.push_back(v);
  }
  return !text.empty() && text.back() != ',';
}

}  // namespace

Point parse_point(const std::string& text, const std::string& option, int* given) {
  std::vector<double> v;
  if (!parse_numbers(text, v) || v.size() < 2 || v.size() > 3)
    throw std::runtime_error(option + " \"" + text + "\": expected X,Y or X,Y,Z (numbers in m, no spaces)");
  if (given) *given = static_cast<int>(v.size());
  return {v[0], v[1], v.size() == 3 ? v[2] : 0.0};
}

std::vector<double> parse_times(const std::string& text, const std::string& option) {
  std::vector<double> v;
  if (!parse_numbers(text, v) || v.empty())
    throw std::runtime_error(option + " \"" + text + "\": expected times in s separated by commas, e.g. 0.5,1");
  return v;
}

ReferenceSpec parse_reference_spec(const std::string& text) {
  const auto eq = text.find('=');
  const std::string column = text.substr(0, eq == std::string::npos ? 0 : eq);
  if (eq == std::string::npos || eq + 1 == text.size() || column.find('.') == std::string::npos)
    throw std::runtime_error("--reference \"" + text +
                             "\": expected MONITOR.QUANTITY=FILE.csv, e.g. top.displacement_y=reference.csv");
  return {column, text.substr(eq + 1)};
}

Method parse_method(const std::string& text) {
  if (text == "nearest") return Method::nearest;
  if (text == "interpolate") return Method::interpolate;
  throw std::runtime_error("--method \"" + text + "\": expected nearest or interpolate");
}

}  // namespace swmpm::post
