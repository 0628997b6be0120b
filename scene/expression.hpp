// Scalar expressions written in scene files (muParser syntax: + - * / ^, sin, cos, exp, sqrt, pi).
#pragma once

#include <string>

namespace swmpm::scene {

/// Value of `expr` at the point (x, y, z); throws std::runtime_error quoting the expression and
/// muParser's message.
double evaluate_expression(const std::string& expr, double x, double y, double z);

}  // namespace swmpm::scene
