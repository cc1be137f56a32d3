#include "dpc/control/extended_jacobian_law.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace dpc {

ExtendedJacobianLaw::ExtendedJacobianLaw(double step, double nullspace_step,
                                         double singular_tolerance, double difference_step)
    : step_(step),
      nullspace_step_(nullspace_step),
      singular_tolerance_(singular_tolerance),
      difference_step_(difference_step),
      solver_(kMaxControls, kMaxControls) {
  if (!std::isfinite(step) || !(step > 0.0)) {
    throw std::invalid_argument(fmt::format("extended Jacobian step must be > 0 (got {})", step));
  }
  if (!std::isfinite(nullspace_step) || nullspace_step < 0.0) {
    throw std::invalid_argument(
        fmt::format("extended Jacobian null-space step must be >= 0 (got {})", nullspace_step));
  }
  if (!std::isfinite(difference_step) || !(difference_step > 0.0)) {
    throw std::invalid_argument(
        fmt::format("extended Jacobian difference step must be > 0 (got {})", difference_step));
  }
}

void ExtendedJacobianLaw::Constraint(const ControlProblem& problem, const ControlVector& phi,
                                     ControlVector* g) {
  problem.chain->ComputePose(phi, &pose_);
  problem.chain->Evaluate(pose_, problem.s_in, &kinematics_, /*with_jacobian=*/false);
  BuildTaskJacobian(*problem.target, kinematics_, problem.s_in, problem.tangent_e1,
                    problem.tangent_e2, &task_jacobian_);
  pseudo_inverse_.Compute(task_jacobian_);
  pseudo_inverse_.NullSpaceProjection(phi, g);
}

ControlStatus ExtendedJacobianLaw::ComputeUpdate(const ControlProblem& problem,
                                                 ControlVector* delta_phi) {
  const int n = problem.control_count();
  const TaskJacobian& a = problem.task_jacobian;
  const int d = static_cast<int>(a.rows());
  delta_phi->setZero(n);

  // Constraint and its derivative.
  const ControlVector& phi = problem.phi();
  Constraint(problem, phi, &g_);
  diagnostics_.rank = pseudo_inverse_.rank();
  diagnostics_.singular_values = pseudo_inverse_.singular_values();
  diagnostics_.nullspace_active = nullspace_step_ > 0.0;
  if (pseudo_inverse_.rank() < d) return ControlStatus::kSingular;
  if (n <= d) {
    // No redundancy, no constraint: the extended system is the task alone.
    diagnostics_.nullspace_active = false;
    pseudo_inverse_.Solve(problem.task_error, delta_phi);
    *delta_phi *= step_;
    return ControlStatus::kOk;
  }
  dg_dphi_.resize(n, n);
  shifted_ = phi;
  for (int c = 0; c < n; ++c) {
    shifted_[c] = phi[c] + difference_step_;
    Constraint(problem, shifted_, &g_plus_);
    shifted_[c] = phi[c] - difference_step_;
    Constraint(problem, shifted_, &g_minus_);
    shifted_[c] = phi[c];
    dg_dphi_.col(c) = (g_plus_ - g_minus_) / (2.0 * difference_step_);
  }

  // Orthonormal basis Z of null(A): the last n − d columns of the full Q of Aᵀ = QR.
  transpose_qr_.compute(a.transpose());
  null_basis_ = transpose_qr_.householderQ();
  const auto z = null_basis_.rightCols(n - d);

  extended_.resize(n, n);
  extended_.topRows(d) = a;
  extended_.bottomRows(n - d).noalias() = z.transpose() * dg_dphi_;
  rhs_.resize(n);
  rhs_.head(d) = step_ * problem.task_error;
  rhs_.tail(n - d).noalias() = -nullspace_step_ * (z.transpose() * g_);

  solver_.setThreshold(singular_tolerance_);
  solver_.compute(extended_);
  if (solver_.rank() < n) {
    delta_phi->setZero(n);
    return ControlStatus::kSingular;
  }
  *delta_phi = solver_.solve(rhs_);
  if (!delta_phi->allFinite()) {
    delta_phi->setZero(n);
    return ControlStatus::kNotFinite;
  }
  return ControlStatus::kOk;
}

}  // namespace dpc
