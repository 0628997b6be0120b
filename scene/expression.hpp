// Scalar expressions written in scene files (muParser syntax: + - * / ^, sin, cos, exp, sqrt, pi).
#pragma once

#include <stdexcept>
#include <string>

#include "scene/scene.hpp"

namespace swmpm::scene {

/// Value of `expr` at the point (x, y, z); throws std::runtime_error quoting the expression and
/// muParser's message.
double evaluate_expression(const std::string& expr, double x, double y, double z);

/// An expression whose value is inf or NaN where it is used (the solver's load functions): the
/// expression, and the message "expression "1/t" is inf at t = 0 s".
class ExpressionValueError : public std::runtime_error {
 public:
  ExpressionValueError(const std::string& expression, const std::string& what)
      : std::runtime_error(what), expression_(expression) {}
  const std::string& expression() const { return expression_; }

 private:
  std::string expression_;
};

/// Component `axis` of body `body`'s initial velocity at `x` [m/s]. A value that is not finite
/// throws SceneError naming the scene file, the JSON path, the expression and the point.
double initial_velocity(const Scene& s, std::size_t body, std::size_t axis, const Vec3& x);

}  // namespace swmpm::scene
