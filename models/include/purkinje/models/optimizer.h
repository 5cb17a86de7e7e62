#pragma once
// The optimizer facade: small dense nonlinear least squares (Ceres'
// Levenberg-Marquardt under the hood). The specular-path solver uses it for
// aspheric surfaces; calibration and users use it as well. Ceres headers
// stay in optimizer.cpp.

#include <functional>
#include <span>
#include <string>

namespace purkinje::optimizer {

struct Options {
  int max_iterations = 50;
  double gradient_tolerance = 1e-18;   // stop when max |J^T r| falls below
  double parameter_tolerance = 1e-16;  // relative step size
  double function_tolerance = 1e-20;   // relative cost decrease
  double initial_trust_region_radius = 1e4;
};

struct Summary {
  bool converged = false;
  int iterations = 0;
  double initial_cost = 0;  // 1/2 |r|^2
  double final_cost = 0;
  std::string message;
};

// Residuals r(x) and optionally the row-major Jacobian dr/dx (num_residuals
// x num_parameters; `jacobian` is null when not needed). Returns false when
// x is outside the function's domain.
using ResidualFunction = std::function<bool(const double* x, double* residuals, double* jacobian)>;

// Minimizes 1/2 |r(x)|^2 starting from x (updated in place).
Summary solve(int num_residuals, std::span<double> x, const ResidualFunction& residuals,
              const Options& options = {});

}  // namespace purkinje::optimizer
