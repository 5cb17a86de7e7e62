// Overhead of the optimizer facade on the small problems of the specular
// solver's hot path: each problem is cheap to evaluate, so the time is
// mostly the facade, std::function and TinySolver's linear algebra.

#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "purkinje/models/optimizer.h"

namespace {

using purkinje::optimizer::ResidualFunction;

// x^2 + y^2 = 2, x = y: root (1, 1), a few Newton-like steps from (2, 0.5).
void BM_Optimizer2x2(benchmark::State& state) {
  const ResidualFunction f = [](const double* x, double* r, double* jacobian) {
    r[0] = x[0] * x[0] + x[1] * x[1] - 2;
    r[1] = x[0] - x[1];
    if (jacobian != nullptr) {
      jacobian[0] = 2 * x[0];
      jacobian[1] = 2 * x[1];
      jacobian[2] = 1;
      jacobian[3] = -1;
    }
    return true;
  };
  int iterations = 0;
  for (auto _ : state) {
    double x[2] = {2, 0.5};
    const auto summary = purkinje::optimizer::solve(2, x, f);
    iterations = summary.iterations;
    benchmark::DoNotOptimize(x);
  }
  state.counters["lm_iterations"] = iterations;
}
BENCHMARK(BM_Optimizer2x2);

// A diagonally dominant 4x4 system with exponentials, root near the origin.
void BM_Optimizer4x4(benchmark::State& state) {
  const ResidualFunction f = [](const double* x, double* r, double* jacobian) {
    for (int i = 0; i < 4; ++i) {
      r[i] = std::exp(x[i]) / 2 - 0.5 - 0.1 * (i + 1);
      for (int j = 0; j < 4; ++j) {
        const double a = i == j ? 4.0 : 1.0 / (1 + i + 2 * j);
        r[i] += a * x[j];
        if (jacobian != nullptr) jacobian[4 * i + j] = a + (i == j ? std::exp(x[i]) / 2 : 0);
      }
    }
    return true;
  };
  int iterations = 0;
  for (auto _ : state) {
    double x[4] = {0, 0, 0, 0};
    const auto summary = purkinje::optimizer::solve(4, x, f);
    iterations = summary.iterations;
    benchmark::DoNotOptimize(x);
  }
  state.counters["lm_iterations"] = iterations;
}
BENCHMARK(BM_Optimizer4x4);

}  // namespace
