#pragma once
// The Moore–Penrose pseudo-inverse of a reduced task Jacobian A (d × n, d = 1 or 2) in closed
// form: no SVD on the real-time path.
//
//   G = A Aᵀ (d × d).  d = 2: eigenvalues λ1 ≥ λ2 ≥ 0 of G in closed form, with
//   det G = Σ_{i<j} (a_1i a_2j − a_1j a_2i)² (Cauchy–Binet: a sum of squares, so λ2 = det/λ1
//   keeps full relative accuracy even when σ2 = √λ2 ≪ σ1).
//     rank 2 (σ2 > tol·σ1):  A⁺ = Aᵀ G⁻¹
//     rank 1:                A⁺ = Aᵀ u uᵀ / λ1      (u: unit eigenvector of λ1)
//     rank 0:                A⁺ = 0
//   d = 1: A⁺ = Aᵀ / (A Aᵀ), or 0 when A = 0.
//
// The singular values of A equal those of the full Jacobian J (A = Eᵀ J with E orthonormal).
// Solve gives A⁺e; NullSpaceProjection gives (I − A⁺A)v, the projection onto null(A) that
// gradient projection uses (paper eq. 12). Neither allocates.

#include "dpc/control/control_problem.h"

namespace dpc {

class TaskPseudoInverse {
 public:
  /// `relative_tolerance`: singular values below relative_tolerance·σ_max count as zero.
  explicit TaskPseudoInverse(double relative_tolerance = 1e-12)
      : relative_tolerance_(relative_tolerance) {}

  /// Real-time. Factorizes `a` (d ≤ 2 rows); keeps a reference to it until the next call.
  void Compute(const TaskJacobian& a);

  int rank() const { return rank_; }
  double sigma_max() const { return sigma_max_; }
  /// The smallest of the d singular values (σ2 for d = 2, σ1 for d = 1).
  double sigma_min() const { return sigma_min_; }
  /// The d × d matrix K with A⁺ = Aᵀ K.
  const Eigen::Matrix2d& k() const { return k_; }

  /// Real-time. x = A⁺ e.
  void Solve(const TaskVector& e, ControlVector* x) const;
  /// Real-time. out = (I − A⁺A) v.
  void NullSpaceProjection(const ControlVector& v, ControlVector* out) const;

 private:
  double relative_tolerance_;
  const TaskJacobian* a_ = nullptr;
  int rows_ = 0;
  int rank_ = 0;
  double sigma_max_ = 0.0;
  double sigma_min_ = 0.0;
  Eigen::Matrix2d k_ = Eigen::Matrix2d::Zero();
};

}  // namespace dpc
