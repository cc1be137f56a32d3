#include "dpc/control/gradient_projection_law.h"

#include <fmt/format.h>

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
  diagnostics_.sigma_max = pseudo_inverse_.sigma_max();
  diagnostics_.sigma_min = pseudo_inverse_.sigma_min();

  pseudo_inverse_.Solve(problem.task_error, delta_phi);
  *delta_phi *= step_;

  const ControlVector& phi = problem.phi();
  const bool active = nullspace_step_ > 0.0 &&
                      (!threshold_ || phi.cwiseAbs().maxCoeff() > *threshold_);
  diagnostics_.nullspace_active = active;
  if (active) {
    pseudo_inverse_.NullSpaceProjection(phi, &nullspace_term_);
    delta_phi->noalias() -= nullspace_step_ * nullspace_term_;
  }
  if (!delta_phi->allFinite()) {
    delta_phi->setZero();
    return ControlStatus::kNotFinite;
  }
  const bool full_rank = pseudo_inverse_.rank() == problem.task_jacobian.rows();
  return full_rank ? ControlStatus::kOk : ControlStatus::kRankDeficient;
}

}  // namespace dpc
