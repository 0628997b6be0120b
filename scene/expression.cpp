#include "scene/expression.hpp"

#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include <muParser.h>

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

}  // namespace swmpm::scene
