// Number and point formatting for messages, comments and file names (postprocess internal).
#pragma once

#include <sstream>
#include <string>

#include "postprocess/postprocess.hpp"

namespace swmpm::post {

/// A number with 6 significant digits, as a person reads it ("0.0125", "1.2e+06").
inline std::string num(double v, int digits = 6) {
  std::ostringstream s;
  s.precision(digits);
  s << v;
  return s.str();
}

/// "(x, y)" or "(x, y, z)".
inline std::string point_text(const Point& x, int dimension) {
  // A stream, not "(" + ...: GCC 12 reports a false -Wrestrict on that concatenation (bug 105329).
  std::ostringstream s;
  s.precision(6);
  s << "(" << x[0] << ", " << x[1];
  if (dimension == 3) s << ", " << x[2];
  s << ")";
  return s.str();
}

}  // namespace swmpm::post
