#include "dpc/control/gradient_projection_law.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dpc {

GradientProjectionLaw::GradientProjectionLaw(double step, double nullspace_step,
                                             std::optional<double> threshold,
                                             double singular_value_tolerance)
    : step_(step),
      nullspace_step_(nullspace_step),
      threshold_(threshold),
      pseudo_inverse_(singular_value_tolerance) {
  if (!std::isfinite(step) || !(step > 0.0)) {
    throw std::invalid_argument(fmt::format("gradient projection step must be > 0 (got {})", step));
  }
  if (!std::isfinite(nullspace_step) || nullspace_step < 0.0) {
    throw std::invalid_argument(
        fmt::format("gradient projection null-space step must be >= 0 (got {})", nullspace_step));
  }
  if (threshold && (!std::isfinite(*threshold) || *threshold < 0.0)) {
    throw std::invalid_argument(
        fmt::format("gradient projection threshold must be >= 0 (got {})", *threshold));
  }
}

ControlStatus GradientProjectionLaw::ComputeUpdate(const ControlProblem& problem,
                                                   ControlVector* delta_phi) {
  pseudo_inverse_.Compute(problem.task_jacobian);
  diagnostics_.rank = pseudo_inverse_.rank();
  diagnostics_.singular_values = pseudo_inverse_.singular_values();

  const ControlVector& phi = problem.phi();
  const int n = static_cast<int>(phi.size());
  bool active = nullspace_step_ > 0.0;
  if (active && threshold_) {
    double largest = 0.0;
    for (int i = 0; i < n; ++i) largest = std::max(largest, std::abs(phi[i]));
    active = largest > *threshold_;
  }
  diagnostics_.nullspace_active = active;
  pseudo_inverse_.GradientProjectionStep(problem.task_error, phi, step_,
                                         active ? nullspace_step_ : 0.0, delta_phi);
  // 0·x is 0 for finite x and NaN for NaN or ±Inf: one branch for the whole vector.
  double sum = 0.0;
  for (int i = 0; i < n; ++i) sum += 0.0 * (*delta_phi)[i];
  if (sum != 0.0) {
    delta_phi->setZero();
    return ControlStatus::kNotFinite;
  }
  const bool full_rank = pseudo_inverse_.rank() == problem.task_jacobian.rows();
  return full_rank ? ControlStatus::kOk : ControlStatus::kRankDeficient;
}

}  // namespace dpc
