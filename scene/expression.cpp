#include "scene/expression.hpp"

#include <cmath>
#include <stdexcept>

#include <muParser.h>

namespace swmpm::scene {

double evaluate_expression(const std::string& expr, double x, double y, double z) {
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
