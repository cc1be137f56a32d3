#pragma once
// The Moore–Penrose pseudo-inverse of a reduced task Jacobian A (d × n, d = 1 or 2) in closed
// form: no iterative SVD on the real-time path.
//
// d = 2, one-sided Jacobi: a single plane rotation U = [u1 u2] of the two rows makes them
// orthogonal, b_i = u_iᵀ A (the rotation diagonalizes G = AAᵀ: tan 2ϑ = 2 g12 / (g22 − g11)).
// That is the exact SVD A = Σ σ_i u_i v_iᵀ with σ_i = |b_i|, v_i = b_i / σ_i. Then
//
//   A⁺ e        = Σ_i b_i (u_iᵀ e) / σ_i²
//   (I − A⁺A) v = v − Σ_i b_i (b_iᵀ v) / σ_i²        (projection onto null A, paper eq. 12)
//
// over the singular values above relative_tolerance·σ1 (rank 2, 1 or 0). Working on the rows
// rather than inverting AAᵀ keeps the accuracy of an SVD near singularities (AAᵀ would square
// the condition number). b2 is re-orthogonalized against b1 so the projector stays idempotent.
// d = 1: A⁺ = Aᵀ / |A|², or 0 when A = 0.
//
// The singular values of the reduced task equal those of the full 3 × n Jacobian (A = EᵀJ with
// E orthonormal and J's columns in E's span). About 20n flops and 3 square roots; no allocation.

#include "dpc/control/control_problem.h"

namespace dpc {

class TaskPseudoInverse {
 public:
  /// `relative_tolerance`: singular values at or below relative_tolerance·σ_max count as zero.
  explicit TaskPseudoInverse(double relative_tolerance = 1e-12)
      : relative_tolerance_(relative_tolerance) {}

  /// Real-time. Factorizes `a` (1 or 2 rows, at most kMaxControls columns).
  void Compute(const TaskJacobian& a);

  int rank() const { return rank_; }
  double sigma_max() const { return sigma_[0]; }
  /// The smallest of the d singular values (σ2 for d = 2, σ1 for d = 1).
  double sigma_min() const { return sigma_[rows_ - 1]; }

  /// Real-time. x = A⁺ e.
  void Solve(const TaskVector& e, ControlVector* x) const;
  /// Real-time. out = (I − A⁺A) v.
  void NullSpaceProjection(const ControlVector& v, ControlVector* out) const;

 private:
  double relative_tolerance_;
  int rows_ = 1;
  int rank_ = 0;
  double sigma_[2] = {0.0, 0.0};
  double inverse_sigma_squared_[2] = {0.0, 0.0};  ///< 0 for dropped singular values
  Eigen::Matrix2d u_ = Eigen::Matrix2d::Identity();  ///< columns u1, u2
  ControlVector b_[2];                               ///< σ_i v_i
};

}  // namespace dpc
