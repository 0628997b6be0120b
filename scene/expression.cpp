#include "scene/expression.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include <muParser.h>

#include "scene/input.hpp"

namespace swmpm::scene {

double evaluate_expression(const std::string& expr, double x, double y, double z) {
  // A plain number (the common case, e.g. "0") needs no parser: building a muParser per particle
  // was most of the seeding time of large scenes.
  {
    char* end = nullptr;
    const double v = std::strtod(expr.c_str(), &end);
    if (end != expr.c_str() && end != nullptr) {
      while (*end == ' ') ++end;
      if (*end == '\0') return v;
    }
  }
  mu::Parser p;
  p.DefineVar("x", &x);
  p.DefineVar("y", &y);
  p.DefineVar("z", &z);
  p.DefineConst("pi", M_PI);
  try {
    p.SetExpr(expr);
    return p.Eval();
  } catch (const mu::Parser::exception_type& e) {
    throw std::runtime_error("expression \"" + expr + "\": " + e.GetMsg());
  }
}

double initial_velocity(const Scene& s, std::size_t body, std::size_t axis, const Vec3& x) {
  const std::string& expr = s.bodies[body].initial.velocity[axis];
  const double v = evaluate_expression(expr, x[0], x[1], x[2]);
  if (std::isfinite(v)) return v;
  char at[160];
  if (s.dimension == 2) std::snprintf(at, sizeof at, "(x, y) = (%.10g, %.10g)", x[0], x[1]);
  else std::snprintf(at, sizeof at, "(x, y, z) = (%.10g, %.10g, %.10g)", x[0], x[1], x[2]);
  throw SceneError({s.source_file + ": /bodies/" + std::to_string(body) + "/initial/velocity/" + std::to_string(axis) +
                    ": got \"" + shortened(expr) + "\", which is " + (std::isnan(v) ? "nan" : v > 0 ? "inf" : "-inf") + " at " +
                    at + " m (a particle of body \"" + s.bodies[body].name + "\"); expected a finite velocity [m/s]"});
}

}  // namespace swmpm::scene
