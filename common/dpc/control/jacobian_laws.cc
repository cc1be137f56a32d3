#include "dpc/control/jacobian_laws.h"

#include <Eigen/LU>
#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace dpc {
namespace {

void RequirePositiveFinite(double value, const char* what) {
  if (!std::isfinite(value) || !(value > 0.0)) {
    throw std::invalid_argument(fmt::format("{} must be finite and > 0 (got {})", what, value));
  }
}

// Solves the square task M x = b, M = task matrix + λI (λ = 0 for the plain inverse):
// 3 × 3 (point target, J itself) or 1 × 1 (set target, nᵀJ). Returns false if singular.
bool SolveSquareTask(const ControlProblem& problem, double damping, double tolerance,
                     ControlVector* x) {
  const int n = problem.control_count();
  if (problem.target->is_point()) {
    if (n != 3) return false;
    const Matrix3 m = problem.kinematics.jacobian.leftCols<3>() + damping * Matrix3::Identity();
    Eigen::FullPivLU<Matrix3> lu(m);
    lu.setThreshold(tolerance);
    if (!lu.isInvertible()) return false;
    *x = lu.solve(problem.PointError());
    return true;
  }
  if (n != 1) return false;
  const double a = problem.task_jacobian(0, 0) + damping;
  const double scale = problem.kinematics.input_generators.col(0).norm() + damping;
  if (!(std::abs(a) > tolerance * scale)) return false;
  x->resize(1);
  (*x)[0] = problem.task_error[0] / a;
  return true;
}

}  // namespace

JacobianLawBase::JacobianLawBase(double step, double singular_value_tolerance)
    : step_(step), pseudo_inverse_(singular_value_tolerance) {
  RequirePositiveFinite(step, "control step");
  RequirePositiveFinite(singular_value_tolerance, "singular value tolerance");
}

void JacobianLawBase::FactorizeTask(const ControlProblem& problem) {
  pseudo_inverse_.Compute(problem.task_jacobian);
  diagnostics_.rank = pseudo_inverse_.rank();
  diagnostics_.singular_values = pseudo_inverse_.singular_values();
}

ControlStatus JacobianLawBase::Finish(ControlStatus status, ControlVector* delta_phi) {
  if (!delta_phi->allFinite()) {
    delta_phi->setZero();
    return ControlStatus::kNotFinite;
  }
  return status;
}

// ---------------------------------------------------------------------------------------------
InverseJacobianLaw::InverseJacobianLaw(double step, double singular_tolerance)
    : JacobianLawBase(step, 1e-12), singular_tolerance_(singular_tolerance) {
  RequirePositiveFinite(singular_tolerance, "inverse singular tolerance");
}

ControlStatus InverseJacobianLaw::ComputeUpdate(const ControlProblem& problem,
                                                ControlVector* delta_phi) {
  FactorizeTask(problem);
  if (!SolveSquareTask(problem, 0.0, singular_tolerance_, delta_phi)) {
    delta_phi->setZero(problem.control_count());
    return ControlStatus::kSingular;
  }
  *delta_phi *= step_;
  return Finish(ControlStatus::kOk, delta_phi);
}

// ---------------------------------------------------------------------------------------------
TransposeJacobianLaw::TransposeJacobianLaw(double step) : JacobianLawBase(step, 1e-12) {}

ControlStatus TransposeJacobianLaw::ComputeUpdate(const ControlProblem& problem,
                                                  ControlVector* delta_phi) {
  FactorizeTask(problem);
  delta_phi->noalias() = step_ * (problem.task_jacobian.transpose() * problem.task_error);
  return Finish(ControlStatus::kOk, delta_phi);
}

// ---------------------------------------------------------------------------------------------
DampedJacobianLaw::DampedJacobianLaw(double step, double damping, double singular_tolerance)
    : JacobianLawBase(step, 1e-12), damping_(damping), singular_tolerance_(singular_tolerance) {
  if (!std::isfinite(damping) || damping < 0.0) {
    throw std::invalid_argument(
        fmt::format("damping must be finite and >= 0 (got {})", damping));
  }
  RequirePositiveFinite(singular_tolerance, "damped singular tolerance");
}

ControlStatus DampedJacobianLaw::ComputeUpdate(const ControlProblem& problem,
                                               ControlVector* delta_phi) {
  FactorizeTask(problem);
  if (!SolveSquareTask(problem, damping_, singular_tolerance_, delta_phi)) {
    delta_phi->setZero(problem.control_count());
    return ControlStatus::kSingular;
  }
  *delta_phi *= step_;
  return Finish(ControlStatus::kOk, delta_phi);
}

// ---------------------------------------------------------------------------------------------
PseudoInverseLaw::PseudoInverseLaw(double step, double singular_value_tolerance)
    : JacobianLawBase(step, singular_value_tolerance) {}

ControlStatus PseudoInverseLaw::ComputeUpdate(const ControlProblem& problem,
                                              ControlVector* delta_phi) {
  FactorizeTask(problem);
  pseudo_inverse_.Solve(problem.task_error, delta_phi);
  *delta_phi *= step_;
  const bool full_rank = pseudo_inverse_.rank() == problem.task_jacobian.rows();
  return Finish(full_rank ? ControlStatus::kOk : ControlStatus::kRankDeficient, delta_phi);
}

// ---------------------------------------------------------------------------------------------
RegularizedLeastSquaresLaw::RegularizedLeastSquaresLaw(double step, double damping)
    : JacobianLawBase(step, 1e-12), damping_(damping) {
  RequirePositiveFinite(damping, "regularized least squares damping");
}

ControlStatus RegularizedLeastSquaresLaw::ComputeUpdate(const ControlProblem& problem,
                                                        ControlVector* delta_phi) {
  FactorizeTask(problem);
  const TaskJacobian& a = problem.task_jacobian;
  const TaskVector& e = problem.task_error;
  if (a.rows() == 1) {
    const double g = a.row(0).squaredNorm() + damping_;
    delta_phi->noalias() = a.row(0).transpose() * (step_ * e[0] / g);
  } else {
    Eigen::Matrix2d g = a.topRows<2>() * a.topRows<2>().transpose();
    g.diagonal().array() += damping_;
    const Eigen::Vector2d y = g.inverse() * Eigen::Vector2d(e[0], e[1]);
    delta_phi->noalias() = step_ * (a.row(0).transpose() * y[0] + a.row(1).transpose() * y[1]);
  }
  return Finish(ControlStatus::kOk, delta_phi);
}

}  // namespace dpc
