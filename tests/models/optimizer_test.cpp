#include "purkinje/models/optimizer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace purkinje {
namespace {

using optimizer::ResidualFunction;

// Checks a callback's analytic Jacobian against central differences, so the
// test problems below are known to be stated correctly.
void expect_jacobian_matches_numeric(const ResidualFunction& f, int num_residuals,
                                     std::vector<double> x) {
  const int n = static_cast<int>(x.size());
  std::vector<double> r(num_residuals), jacobian(num_residuals * n);
  ASSERT_TRUE(f(x.data(), r.data(), jacobian.data()));
  for (int p = 0; p < n; ++p) {
    const double h = 1e-6 * std::max(1.0, std::abs(x[p]));
    std::vector<double> plus = x, minus = x, r_plus(num_residuals), r_minus(num_residuals);
    plus[p] += h;
    minus[p] -= h;
    ASSERT_TRUE(f(plus.data(), r_plus.data(), nullptr));
    ASSERT_TRUE(f(minus.data(), r_minus.data(), nullptr));
    for (int i = 0; i < num_residuals; ++i) {
      const double numeric = (r_plus[i] - r_minus[i]) / (2 * h);
      EXPECT_NEAR(jacobian[i * n + p], numeric, 1e-6 * std::max(1.0, std::abs(numeric)))
          << "residual " << i << ", parameter " << p;
    }
  }
}

// Rosenbrock's valley in least-squares form over 2k parameters: residuals
// 10 (x[2i+1] - x[2i]^2) and 1 - x[2i]; the minimum is all ones, cost 0.
ResidualFunction rosenbrock(int num_parameters) {
  return [num_parameters](const double* x, double* r, double* jacobian) {
    if (jacobian != nullptr) std::fill_n(jacobian, num_parameters * num_parameters, 0.0);
    for (int i = 0; i < num_parameters; i += 2) {
      r[i] = 10 * (x[i + 1] - x[i] * x[i]);
      r[i + 1] = 1 - x[i];
      if (jacobian != nullptr) {
        jacobian[i * num_parameters + i] = -20 * x[i];
        jacobian[i * num_parameters + i + 1] = 10;
        jacobian[(i + 1) * num_parameters + i] = -1;
      }
    }
    return true;
  };
}

// A square nonlinear system exp(x_i) / 2 + sum_j A_ij x_j = b_i, with b made
// from a chosen root so that the solution is known exactly.
struct ExponentialSystem {
  int n;
  std::vector<double> root;

  double a(int i, int j) const { return i == j ? 4.0 : 1.0 / (1 + i + 2 * j); }
  double b(int i) const {
    double value = std::exp(root[i]) / 2;
    for (int j = 0; j < n; ++j) value += a(i, j) * root[j];
    return value;
  }
  ResidualFunction residuals() const {
    return [this](const double* x, double* r, double* jacobian) {
      for (int i = 0; i < n; ++i) {
        r[i] = std::exp(x[i]) / 2 - b(i);
        for (int j = 0; j < n; ++j) {
          r[i] += a(i, j) * x[j];
          if (jacobian != nullptr) {
            jacobian[i * n + j] = a(i, j) + (i == j ? std::exp(x[i]) / 2 : 0);
          }
        }
      }
      return true;
    };
  }
};

TEST(Optimizer, FindsTheRosenbrockMinimum) {
  const ResidualFunction f = rosenbrock(2);
  expect_jacobian_matches_numeric(f, 2, {-1.2, 1});
  std::vector<double> x{-1.2, 1};
  const optimizer::Summary summary = optimizer::solve(2, x, f);
  EXPECT_TRUE(summary.converged) << summary.message;
  EXPECT_NEAR(x[0], 1, 1e-12);
  EXPECT_NEAR(x[1], 1, 1e-12);
  // 1/2 (10 (1 - 1.44)^2 ... ): r = (10 (1 - 1.44), 2.2) = (-4.4, 2.2).
  EXPECT_NEAR(summary.initial_cost, (4.4 * 4.4 + 2.2 * 2.2) / 2, 1e-12);
  EXPECT_LT(summary.final_cost, 1e-24);
  EXPECT_GT(summary.iterations, 1);
  EXPECT_FALSE(summary.message.empty());
}

TEST(Optimizer, SolvesLinearLeastSquaresAsTheNormalEquations) {
  // Line y = a + b t through (0,1), (1,3), (2,2), (3,5), (4,4). Normal
  // equations [5 10; 10 30] (a, b) = (15, 38) give a = 1.4, b = 0.8, and
  // residuals (0.4, -0.8, 1.0, -1.2, 0.6), so cost 3.6 / 2.
  const std::vector<double> t{0, 1, 2, 3, 4}, y{1, 3, 2, 5, 4};
  const ResidualFunction line = [&](const double* x, double* r, double* jacobian) {
    for (int i = 0; i < 5; ++i) {
      r[i] = x[0] + x[1] * t[i] - y[i];
      if (jacobian != nullptr) {
        jacobian[2 * i] = 1;
        jacobian[2 * i + 1] = t[i];
      }
    }
    return true;
  };
  expect_jacobian_matches_numeric(line, 5, {0.3, -2});
  std::vector<double> x{0, 0};
  const optimizer::Summary summary = optimizer::solve(5, x, line);
  EXPECT_TRUE(summary.converged) << summary.message;
  // With a nonzero minimum cost, cost changes below its rounding (~1e-16)
  // cannot be seen, so the damped steps stop short by about 1e-12.
  EXPECT_NEAR(x[0], 1.4, 1e-10);
  EXPECT_NEAR(x[1], 0.8, 1e-10);
  EXPECT_NEAR(summary.final_cost, 1.8, 1e-12);
  EXPECT_NEAR(summary.initial_cost, (1 + 9 + 4 + 25 + 16) / 2.0, 1e-12);
}

TEST(Optimizer, SolvesSquareSystemsOfEverySmallSize) {
  // 3 and 4 take fixed-size paths, 1, 5 and 8 the dynamic TinySolver.
  for (int n : {1, 3, 4, 5, 8}) {
    ExponentialSystem system{n, {}};
    for (int i = 0; i < n; ++i) system.root.push_back(0.7 * std::sin(1.0 + 2.0 * i));
    const ResidualFunction f = system.residuals();
    expect_jacobian_matches_numeric(f, n, std::vector<double>(n, 0.3));
    std::vector<double> x(n, 0.0);
    const optimizer::Summary summary = optimizer::solve(n, x, f);
    EXPECT_TRUE(summary.converged) << "n = " << n << ": " << summary.message;
    for (int i = 0; i < n; ++i) EXPECT_NEAR(x[i], system.root[i], 1e-12) << "n = " << n;
  }
}

TEST(Optimizer, SolvesAFourParameterProblem) {
  // Distance residuals from a point to four anchors: the point at known
  // distances from the corners of a tetrahedron, plus a fourth unknown scale
  // s that multiplies all distances. Unknowns (x, y, z, s); the truth is
  // (1, 2, 3, 2).
  const std::vector<std::array<double, 3>> anchors{{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {0, 0, 10}};
  const std::array<double, 4> truth{1, 2, 3, 2};
  std::vector<double> measured;
  for (const auto& anchor : anchors) {
    const double dx = truth[0] - anchor[0], dy = truth[1] - anchor[1], dz = truth[2] - anchor[2];
    measured.push_back(std::sqrt(dx * dx + dy * dy + dz * dz) / truth[3]);
  }
  const ResidualFunction f = [&](const double* x, double* r, double* jacobian) {
    for (int i = 0; i < 4; ++i) {
      const double d[3] = {x[0] - anchors[i][0], x[1] - anchors[i][1], x[2] - anchors[i][2]};
      const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      r[i] = length - x[3] * measured[i];
      if (jacobian != nullptr) {
        for (int k = 0; k < 3; ++k) jacobian[4 * i + k] = d[k] / length;
        jacobian[4 * i + 3] = -measured[i];
      }
    }
    return true;
  };
  expect_jacobian_matches_numeric(f, 4, {2, 1, 1, 1.5});
  std::vector<double> x{2, 1, 1, 1.5};
  const optimizer::Summary summary = optimizer::solve(4, x, f);
  EXPECT_TRUE(summary.converged) << summary.message;
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(x[i], truth[i], 1e-10) << i;
}

// Twenty parameters go to the dense TinySolver (with a Jacobian too large
// for its inline buffer), forty to ceres::Problem.
TEST(Optimizer, SolvesRosenbrockInTwentyAndFortyParameters) {
  for (const int n : {20, 40}) {
    const ResidualFunction f = rosenbrock(n);
    std::vector<double> x0(n);
    for (int i = 0; i < n; i += 2) {
      x0[i] = -1.2;
      x0[i + 1] = 1;
    }
    expect_jacobian_matches_numeric(f, n, x0);
    std::vector<double> x = x0;
    const optimizer::Summary summary = optimizer::solve(n, x, f);
    EXPECT_TRUE(summary.converged) << n << ": " << summary.message;
    for (double xi : x) EXPECT_NEAR(xi, 1, 1e-10) << n;
    EXPECT_NEAR(summary.initial_cost, n / 2 * (4.4 * 4.4 + 2.2 * 2.2) / 2, 1e-10) << n;
    EXPECT_LT(summary.final_cost, 1e-20) << n;
    EXPECT_GT(summary.iterations, 1) << n;
  }
}

// log(x_i) = c_i has its root at exp(c_i), and a full Gauss-Newton step from
// far right of it lands at negative x, outside the domain.
ResidualFunction logarithms(int n, int* domain_errors) {
  return [n, domain_errors](const double* x, double* r, double* jacobian) {
    for (int i = 0; i < n; ++i) {
      if (!(x[i] > 0)) {
        ++*domain_errors;
        return false;
      }
    }
    for (int i = 0; i < n; ++i) {
      r[i] = std::log(x[i]) - 1.0 / (1 + i);
      if (jacobian != nullptr) {
        for (int j = 0; j < n; ++j) jacobian[i * n + j] = i == j ? 1 / x[i] : 0;
      }
    }
    return true;
  };
}

TEST(Optimizer, StepsBackFromDomainErrors) {
  for (int n : {1, 2, 12}) {  // dynamic TinySolver, fixed 2x2 and Ceres' Problem
    int domain_errors = 0;
    const ResidualFunction f = logarithms(n, &domain_errors);
    std::vector<double> x(n, 100.0);
    const optimizer::Summary summary = optimizer::solve(n, x, f);
    EXPECT_GT(domain_errors, 0) << "n = " << n << ": the test must hit the domain edge";
    EXPECT_TRUE(summary.converged) << "n = " << n << ": " << summary.message;
    for (int i = 0; i < n; ++i) EXPECT_NEAR(x[i], std::exp(1.0 / (1 + i)), 1e-10) << "n = " << n;
  }
}

TEST(Optimizer, ReportsADomainErrorAtTheStartWithoutCrashing) {
  for (int n : {1, 2, 12}) {
    int domain_errors = 0;
    const ResidualFunction f = logarithms(n, &domain_errors);
    std::vector<double> x(n, -1.0);
    const optimizer::Summary summary = optimizer::solve(n, x, f);
    EXPECT_FALSE(summary.converged) << "n = " << n;
    EXPECT_FALSE(summary.message.empty());
    EXPECT_FALSE(std::isnan(summary.final_cost));
    EXPECT_EQ(x, std::vector<double>(n, -1.0)) << "n = " << n;
  }
}

TEST(Optimizer, ReportsAJacobianThatCannotBeEvaluated) {
  int jacobian_requests = 0;
  const ResidualFunction f = [&](const double* x, double* r, double* jacobian) {
    r[0] = x[0] - 1;
    r[1] = x[1] - 2;
    if (jacobian != nullptr && ++jacobian_requests > 1) return false;
    if (jacobian != nullptr) {
      jacobian[0] = jacobian[3] = 1;
      jacobian[1] = jacobian[2] = 0;
    }
    return true;
  };
  std::vector<double> x{5, 5};
  const optimizer::Summary summary = optimizer::solve(2, x, f);
  EXPECT_FALSE(summary.converged);
  EXPECT_NE(summary.message.find("Jacobian"), std::string::npos) << summary.message;
  EXPECT_TRUE(std::isfinite(x[0]) && std::isfinite(x[1]));
}

TEST(Optimizer, ReportsNonConvergenceWhenIterationsRunOut) {
  for (int n : {2, 20}) {
    const ResidualFunction f = rosenbrock(n);
    std::vector<double> x(n);
    for (int i = 0; i < n; i += 2) {
      x[i] = -1.2;
      x[i + 1] = 1;
    }
    optimizer::Options options;
    options.max_iterations = 1;
    const optimizer::Summary summary = optimizer::solve(n, x, f, options);
    EXPECT_FALSE(summary.converged) << "n = " << n << ": " << summary.message;
    EXPECT_LE(summary.iterations, 1) << "n = " << n;
    EXPECT_GT(summary.final_cost, 1e-3) << "n = " << n;
  }
}

TEST(Optimizer, AllowsAResidualFunctionToSolveItsOwnProblem) {
  // Outer: find x with cbrt(x) = 2, where cbrt comes from an inner solve of
  // y^3 = x. Both are 1x1 problems sharing the dynamic-size solver.
  const ResidualFunction outer = [](const double* x, double* r, double* jacobian) {
    std::vector<double> y{1};
    const double target = x[0];
    const ResidualFunction inner = [target](const double* v, double* s, double* j) {
      s[0] = v[0] * v[0] * v[0] - target;
      if (j != nullptr) j[0] = 3 * v[0] * v[0];
      return true;
    };
    if (!optimizer::solve(1, y, inner).converged) return false;
    r[0] = y[0] - 2;
    if (jacobian != nullptr) jacobian[0] = 1 / (3 * y[0] * y[0]);
    return true;
  };
  std::vector<double> x{3};
  const optimizer::Summary summary = optimizer::solve(1, x, outer);
  EXPECT_TRUE(summary.converged) << summary.message;
  EXPECT_NEAR(x[0], 8, 1e-9);
}

// Three unknowns, more residuals: the fixed-size normal matrix path (one
// frame's cornea centre). The plane z = a + b x + c y through the corners
// of the unit square, lifted by (+d, -d, -d, +d): that pattern is
// orthogonal to the columns 1, x and y, so the least-squares plane is the
// unlifted one, (1, 2, -3), and the cost 4 d^2 / 2.
ResidualFunction lifted_plane(double d) {
  return [d](const double* p, double* r, double* jacobian) {
    const double xs[4] = {0, 1, 0, 1}, ys[4] = {0, 0, 1, 1}, lift[4] = {d, -d, -d, d};
    for (int i = 0; i < 4; ++i) {
      r[i] = p[0] + p[1] * xs[i] + p[2] * ys[i] - (1 + 2 * xs[i] - 3 * ys[i] + lift[i]);
      if (jacobian != nullptr) {
        jacobian[3 * i] = 1;
        jacobian[3 * i + 1] = xs[i];
        jacobian[3 * i + 2] = ys[i];
      }
    }
    return true;
  };
}

TEST(Optimizer, FitsThreeUnknownsToMoreResiduals) {
  const ResidualFunction plane = lifted_plane(0.5);
  expect_jacobian_matches_numeric(plane, 4, {0.2, -1, 4});
  std::vector<double> x{0, 0, 0};
  const optimizer::Summary summary = optimizer::solve(4, x, plane);
  EXPECT_TRUE(summary.converged) << summary.message;
  EXPECT_NEAR(x[0], 1, 1e-10);
  EXPECT_NEAR(x[1], 2, 1e-10);
  EXPECT_NEAR(x[2], -3, 1e-10);
  EXPECT_NEAR(summary.final_cost, 0.5, 1e-12);
}

TEST(Optimizer, NestsThreeUnknownSolvesInEachOther) {
  // Each outer evaluation fits the plane again (the same solver size,
  // so the inner solve must get a solver of its own); the outer problem
  // pulls x onto that plane's coefficients, with a fourth residual of 0.
  int inner_solves = 0;
  const ResidualFunction outer = [&](const double* x, double* r, double* jacobian) {
    std::vector<double> plane{0, 0, 0};
    if (!optimizer::solve(4, plane, lifted_plane(0.25)).converged) return false;
    ++inner_solves;
    for (int k = 0; k < 3; ++k) r[k] = x[k] - plane[k];
    r[3] = 0;
    if (jacobian != nullptr) {
      std::fill_n(jacobian, 12, 0.0);
      for (int k = 0; k < 3; ++k) jacobian[4 * k] = 1;  // row k, column k
    }
    return true;
  };
  std::vector<double> x{5, 5, 5};
  const optimizer::Summary summary = optimizer::solve(4, x, outer);
  EXPECT_TRUE(summary.converged) << summary.message;
  EXPECT_GT(inner_solves, 1);
  EXPECT_NEAR(x[0], 1, 1e-9);
  EXPECT_NEAR(x[1], 2, 1e-9);
  EXPECT_NEAR(x[2], -3, 1e-9);
}

TEST(Optimizer, ReportsAJacobianThatCannotBeEvaluatedWithThreeUnknowns) {
  const ResidualFunction plane = lifted_plane(0.5);
  int jacobian_requests = 0;
  const ResidualFunction failing = [&](const double* x, double* r, double* jacobian) {
    if (jacobian != nullptr && ++jacobian_requests > 1) return false;
    return plane(x, r, jacobian);
  };
  std::vector<double> x{5, 5, 5};
  const optimizer::Summary summary = optimizer::solve(4, x, failing);
  EXPECT_FALSE(summary.converged);
  EXPECT_NE(summary.message.find("Jacobian"), std::string::npos) << summary.message;
  for (const double v : x) EXPECT_TRUE(std::isfinite(v));
}

TEST(Optimizer, RejectsEmptyProblemsByName) {
  std::vector<double> x{1};
  const ResidualFunction f = [](const double*, double*, double*) { return true; };
  EXPECT_THROW(optimizer::solve(0, x, f), std::invalid_argument);
  std::vector<double> none;
  EXPECT_THROW(optimizer::solve(1, none, f), std::invalid_argument);
  try {
    optimizer::solve(-2, x, f);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("num_residuals = -2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace purkinje
