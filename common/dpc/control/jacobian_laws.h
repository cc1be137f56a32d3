#pragma once
// The paper's Jacobian control laws (section III.A–B), each Δφ = μ·(…) with step μ:
//
//   InverseJacobianLaw        Δφ = μ J⁻¹ ΔS                   square task only; reports singular
//   TransposeJacobianLaw      Δφ = μ Jᵀ ΔS
//   DampedJacobianLaw         Δφ = μ (J + λI)⁻¹ ΔS            square task only (paper's form)
//   PseudoInverseLaw          Δφ = μ J⁺ ΔS                    minimum-norm solution
//   RegularizedLeastSquaresLaw Δφ = μ Jᵀ(JJᵀ + λI)⁻¹ ΔS        minimizes ‖JΔφ − ΔS‖² + λ‖Δφ‖²
//
// J and ΔS stand for the task: (J, S* − S_out) for a point target, (nᵀJ, c − n·S_out) for a set.
// Transpose, pseudo-inverse and RLS work on the reduced task (control_problem.h), which gives
// exactly the same Δφ as the 3-D formulas. Inverse and damped need the square matrix itself:
// J (3 × 3, a point target with 3 controls) or nᵀJ (1 × 1, a set target with 1 control). Every
// 3-stage J is singular (rank ≤ 2, its columns are ⊥ S_out; paper eq. 7), so the inverse law
// reports kSingular on every sample of a point-target run and applies nothing: the paper's point.
// Gradient projection is in gradient_projection_law.h.

#include "dpc/control/control_law.h"
#include "dpc/control/task_pseudo_inverse.h"

namespace dpc {

/// Base for the laws here: holds the step and fills the singular-value diagnostics.
class JacobianLawBase : public ControlLaw {
 protected:
  /// Throws std::invalid_argument unless step is finite and > 0.
  explicit JacobianLawBase(double step, double singular_value_tolerance);
  /// Factorizes the task Jacobian and records rank and singular values in diagnostics_.
  void FactorizeTask(const ControlProblem& problem);
  /// Zeroes Δφ and returns kNotFinite if it has NaN/Inf; otherwise returns `status`.
  static ControlStatus Finish(ControlStatus status, ControlVector* delta_phi);

  double step_;
  TaskPseudoInverse pseudo_inverse_;
};

class InverseJacobianLaw final : public JacobianLawBase {
 public:
  /// `singular_tolerance`: the square task matrix counts as singular when its smallest LU pivot
  /// is below singular_tolerance × the largest.
  explicit InverseJacobianLaw(double step, double singular_tolerance = 1e-10);
  ControlStatus ComputeUpdate(const ControlProblem& problem, ControlVector* delta_phi) override;
  std::string_view name() const override { return "inverse"; }

 private:
  double singular_tolerance_;
};

class TransposeJacobianLaw final : public JacobianLawBase {
 public:
  explicit TransposeJacobianLaw(double step);
  ControlStatus ComputeUpdate(const ControlProblem& problem, ControlVector* delta_phi) override;
  std::string_view name() const override { return "transpose"; }
  bool needs_jacobian() const override { return false; }
};

class DampedJacobianLaw final : public JacobianLawBase {
 public:
  /// Throws unless damping λ is finite and ≥ 0.
  DampedJacobianLaw(double step, double damping, double singular_tolerance = 1e-10);
  ControlStatus ComputeUpdate(const ControlProblem& problem, ControlVector* delta_phi) override;
  std::string_view name() const override { return "damped"; }

 private:
  double damping_;
  double singular_tolerance_;
};

class PseudoInverseLaw final : public JacobianLawBase {
 public:
  explicit PseudoInverseLaw(double step, double singular_value_tolerance = 1e-12);
  ControlStatus ComputeUpdate(const ControlProblem& problem, ControlVector* delta_phi) override;
  std::string_view name() const override { return "pinv"; }
  bool needs_jacobian() const override { return false; }
};

class RegularizedLeastSquaresLaw final : public JacobianLawBase {
 public:
  /// Throws unless damping λ is finite and > 0.
  RegularizedLeastSquaresLaw(double step, double damping);
  ControlStatus ComputeUpdate(const ControlProblem& problem, ControlVector* delta_phi) override;
  std::string_view name() const override { return "rls"; }
  bool needs_jacobian() const override { return false; }

 private:
  double damping_;
};

}  // namespace dpc
