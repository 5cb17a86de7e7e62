#include "purkinje/models/optimizer.h"

#include <ceres/ceres.h>
#include <ceres/tiny_solver.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace purkinje::optimizer {

namespace {

// Problems with up to this many parameters go to ceres::TinySolver
// (dense normal equations; no heap allocation for the common fixed sizes),
// whatever their number of residuals; larger ones to ceres::Problem, whose
// set-up alone costs tens of microseconds.
constexpr int max_tiny_parameters = 32;

// Adapts a ResidualFunction to TinySolver's functor interface. TinySolver
// wants a column-major Jacobian; ours is row-major. It also ignores the
// return value of its residual-only evaluations, so a domain error there is
// made an infinite cost, which the trust region rejects; and on a Jacobian
// evaluation it would proceed with stale state, so a failure there is
// recorded and reported as a zero gradient, which stops the solve at once.
//
// TinySolver's function tolerance is absolute, on twice the cost change;
// ours is relative to the current cost, as in Ceres. Every Jacobian
// evaluation is at a newly accepted point, so that is where the absolute
// tolerance is refreshed.
template <int R, int P>
struct TinyFunction {
  using Scalar = double;
  enum { NUM_RESIDUALS = R, NUM_PARAMETERS = P };

  const ResidualFunction* function;
  int num_residuals;
  int num_parameters;
  double relative_function_tolerance;
  double* absolute_function_tolerance;  // the solver's option
  mutable bool jacobian_evaluation_failed = false;
  // Ours, row-major: members, so that a residual function that itself
  // solves (nested) cannot overwrite them; small ones without allocating,
  // for the specular solver's hot path.
  mutable std::array<double, 64> small_row_major{};
  mutable std::vector<double> large_row_major{};

  int NumResiduals() const { return num_residuals; }
  int NumParameters() const { return num_parameters; }

  bool operator()(const double* x, double* residuals, double* jacobian) const {
    if (jacobian == nullptr) {
      if ((*function)(x, residuals, nullptr)) return true;
      std::fill_n(residuals, num_residuals, std::numeric_limits<double>::infinity());
      return false;
    }
    const size_t size = static_cast<size_t>(num_residuals) * num_parameters;
    if (size > small_row_major.size()) large_row_major.resize(size);
    double* row_major = size > small_row_major.size() ? large_row_major.data() : small_row_major.data();
    if (!(*function)(x, residuals, row_major)) {
      jacobian_evaluation_failed = true;
      std::fill_n(residuals, num_residuals, 0.0);
      std::fill_n(jacobian, num_residuals * num_parameters, 0.0);
      return true;
    }
    double squared_norm = 0;
    for (int r = 0; r < num_residuals; ++r) {
      squared_norm += residuals[r] * residuals[r];
      for (int p = 0; p < num_parameters; ++p) {
        jacobian[p * num_residuals + r] = row_major[r * num_parameters + p];
      }
    }
    *absolute_function_tolerance = relative_function_tolerance * squared_norm;
    return true;
  }
};

// Kept within std::string's small-buffer size (15 characters) so that a
// solve on the hot path does not allocate for its message.
template <typename Solver>
const char* describe(typename Solver::Status status) {
  switch (status) {
    case Solver::GRADIENT_TOO_SMALL: return "gradient tol";
    case Solver::RELATIVE_STEP_SIZE_TOO_SMALL: return "parameter tol";
    case Solver::COST_TOO_SMALL: return "zero cost";
    case Solver::HIT_MAX_ITERATIONS: return "max iterations";
    case Solver::COST_CHANGE_TOO_SMALL: return "function tol";
  }
  return "unknown status";
}

template <int R, int P>
Summary solve_tiny(int num_residuals, std::span<double> x, const ResidualFunction& residuals,
                   const Options& options) {
  using Function = TinyFunction<R, P>;
  using Solver = ceres::TinySolver<Function>;
  const int num_parameters = static_cast<int>(x.size());

  // Fixed sizes live on the stack. Dynamic sizes would allocate on every
  // call, so they reuse one solver per thread (one per size pattern),
  // unless a residual function itself calls solve (then the nested call
  // gets its own).
  static thread_local bool shared_solver_busy = false;
  std::optional<Solver> own_solver;
  Solver* solver_pointer = nullptr;
  bool uses_shared_solver = false;
  if constexpr (R == Eigen::Dynamic || P == Eigen::Dynamic) {
    static thread_local Solver shared_solver;
    if (!shared_solver_busy) {
      solver_pointer = &shared_solver;
      uses_shared_solver = shared_solver_busy = true;
    }
  }
  if (solver_pointer == nullptr) solver_pointer = &own_solver.emplace();
  struct Release {
    bool active;
    ~Release() {
      if (active) shared_solver_busy = false;
    }
  } release{uses_shared_solver};
  Solver& solver = *solver_pointer;
  // TinySolver runs iterations 1 .. max_num_iterations - 1.
  solver.options.max_num_iterations =
      std::min(options.max_iterations, std::numeric_limits<int>::max() - 1) + 1;
  solver.options.gradient_tolerance = options.gradient_tolerance;
  solver.options.parameter_tolerance = options.parameter_tolerance;
  solver.options.initial_trust_region_radius = options.initial_trust_region_radius;
  // Only an exact zero counts as "cost too small": the specular solver needs
  // residuals far below TinySolver's default threshold of machine epsilon.
  solver.options.cost_threshold = std::numeric_limits<double>::min();
  Function function{&residuals, num_residuals, num_parameters, options.function_tolerance,
                    &solver.options.function_tolerance};

  typename Solver::Parameters parameters;
  if constexpr (P == Eigen::Dynamic) parameters.resize(num_parameters);
  for (int i = 0; i < num_parameters; ++i) parameters[i] = x[i];
  const auto& tiny = solver.Solve(function, &parameters);
  for (int i = 0; i < num_parameters; ++i) x[i] = parameters[i];

  Summary summary;
  summary.initial_cost = tiny.initial_cost;
  summary.final_cost = tiny.final_cost;
  summary.iterations = std::min(tiny.iterations, options.max_iterations);
  summary.converged = tiny.status != Solver::HIT_MAX_ITERATIONS;
  summary.message = describe<Solver>(tiny.status);
  if (function.jacobian_evaluation_failed) {
    summary.converged = false;
    std::vector<double> r(static_cast<size_t>(num_residuals));
    double cost = std::numeric_limits<double>::infinity();
    if (residuals(x.data(), r.data(), nullptr)) {
      cost = 0;
      for (int i = 0; i < num_residuals; ++i) cost += r[i] * r[i] / 2;
    }
    summary.final_cost = cost;
    if (tiny.iterations == 0) {
      summary.initial_cost = cost;
      summary.message = "residual function failed at the initial point (outside its domain?)";
    } else {
      summary.message = "residual function failed while evaluating the Jacobian";
    }
  }
  return summary;
}

class CallbackCost final : public ceres::DynamicCostFunction {
 public:
  CallbackCost(const ResidualFunction& function, int num_residuals, int num_parameters)
      : function_(function) {
    AddParameterBlock(num_parameters);
    SetNumResiduals(num_residuals);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    // One parameter block, so Ceres' row-major block Jacobian is ours.
    return function_(parameters[0], residuals, jacobians != nullptr ? jacobians[0] : nullptr);
  }

 private:
  const ResidualFunction& function_;
};

Summary solve_large(int num_residuals, std::span<double> x, const ResidualFunction& residuals,
                    const Options& options) {
  // Ceres would log an error for a starting point outside the domain; the
  // caller gets that in the summary instead.
  {
    std::vector<double> r(static_cast<size_t>(num_residuals));
    if (!residuals(x.data(), r.data(), nullptr)) {
      Summary summary;
      summary.initial_cost = summary.final_cost = std::numeric_limits<double>::infinity();
      summary.message = "residual function failed at the initial point (outside its domain?)";
      return summary;
    }
  }
  CallbackCost cost(residuals, num_residuals, static_cast<int>(x.size()));
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  problem.AddResidualBlock(&cost, nullptr, x.data());

  ceres::Solver::Options solver_options;
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.gradient_tolerance = options.gradient_tolerance;
  solver_options.parameter_tolerance = options.parameter_tolerance;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.initial_trust_region_radius = options.initial_trust_region_radius;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  std::string error;
  if (!solver_options.IsValid(&error)) {
    throw std::invalid_argument("optimizer::solve: invalid options: " + error);
  }

  ceres::Solver::Summary ceres_summary;
  ceres::Solve(solver_options, &problem, &ceres_summary);

  Summary summary;
  summary.converged = ceres_summary.termination_type == ceres::CONVERGENCE;
  // Ceres lists iteration 0, the evaluation at the starting point.
  summary.iterations = std::max(0, static_cast<int>(ceres_summary.iterations.size()) - 1);
  summary.initial_cost = ceres_summary.initial_cost;
  summary.final_cost = ceres_summary.final_cost;
  summary.message = ceres_summary.message;
  if (ceres_summary.termination_type == ceres::FAILURE) {
    // Ceres leaves the costs at -1 when it cannot evaluate x0.
    if (summary.initial_cost < 0) summary.initial_cost = std::numeric_limits<double>::infinity();
    if (summary.final_cost < 0) summary.final_cost = std::numeric_limits<double>::infinity();
  }
  return summary;
}

void check_arguments(int num_residuals, std::span<double> x, const Options& options) {
  std::ostringstream out;
  if (num_residuals <= 0) {
    out << "optimizer::solve: num_residuals = " << num_residuals << ": must be > 0";
  } else if (x.empty()) {
    out << "optimizer::solve: the parameter vector is empty: it needs at least one parameter";
  } else if (options.max_iterations < 0) {
    out << "optimizer::solve: max_iterations = " << options.max_iterations << ": must be >= 0";
  } else if (!(options.initial_trust_region_radius > 0)) {
    out << "optimizer::solve: initial_trust_region_radius = "
        << options.initial_trust_region_radius << ": must be > 0";
  } else if (!(options.gradient_tolerance >= 0) || !(options.parameter_tolerance >= 0) ||
             !(options.function_tolerance >= 0)) {
    out << "optimizer::solve: tolerances (gradient " << options.gradient_tolerance
        << ", parameter " << options.parameter_tolerance << ", function "
        << options.function_tolerance << "): must be >= 0";
  } else {
    return;
  }
  throw std::invalid_argument(out.str());
}

}  // namespace

Summary solve(int num_residuals, std::span<double> x, const ResidualFunction& residuals,
              const Options& options) {
  check_arguments(num_residuals, x, options);
  const int num_parameters = static_cast<int>(x.size());
  if (num_parameters > max_tiny_parameters) {
    return solve_large(num_residuals, x, residuals, options);
  }
  if (num_residuals == num_parameters) {
    switch (num_parameters) {
      case 2: return solve_tiny<2, 2>(num_residuals, x, residuals, options);
      case 3: return solve_tiny<3, 3>(num_residuals, x, residuals, options);
      case 4: return solve_tiny<4, 4>(num_residuals, x, residuals, options);
      default: break;
    }
  }
  // One frame's cornea centre (and the like): a 3 x 3 normal matrix on
  // the stack, not a blocked product and a dynamic factorization.
  if (num_parameters == 3) return solve_tiny<Eigen::Dynamic, 3>(num_residuals, x, residuals, options);
  return solve_tiny<Eigen::Dynamic, Eigen::Dynamic>(num_residuals, x, residuals, options);
}

}  // namespace purkinje::optimizer
