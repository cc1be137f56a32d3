#pragma once
// The Moore–Penrose pseudo-inverse of a reduced task Jacobian A (d × n, d = 1 or 2) in closed
// form: no iterative SVD on the real-time path.
//
// Both results are written through the rows b_i of a matrix B and a 2 × 2 matrix:
//
//   A⁺ e        = Bᵀ (S e)
//   (I − A⁺A) v = v − Bᵀ (P (B v))              (projection onto null A, paper eq. 10)
//
// d = 2, well conditioned (det G > 1e-6·(tr G)², i.e. σ2/σ1 ≳ 1e-3, G = AAᵀ): the normal
// equations, B = A and S = P = G⁻¹ (one division). With κ(G) < 1e6 the result is within ~1e-10
// of the SVD's.
// d = 2, near a singularity: one-sided Jacobi. A single plane rotation U = [u1 u2] of the two
// rows makes them orthogonal, b_i = u_iᵀ A (tan 2ϑ = 2 g12 / (g22 − g11)): the exact SVD
// A = Σ σ_i u_i v_iᵀ with σ_i = |b_i|. Then S = diag(1/σ_i²) Uᵀ and P = diag(1/σ_i²), over the
// singular values above relative_tolerance·σ1 (rank 2, 1 or 0). Working on the rows keeps the
// accuracy of an SVD where inverting G would square the condition number. b2 is
// re-orthogonalized against b1 so the projector stays idempotent.
// d = 1: B = A, S = P = 1/|A|² (or 0 when A = 0).
//
// The singular values of the reduced task equal those of the full 3 × n Jacobian (A = EᵀJ with
// E orthonormal and J's columns in E's span). No allocation.
//
// Singularity-robust damping (ComputeDamped; Nakamura & Hanafusa 1986, Maciejewski 1988): the
// damped least-squares inverse A_λ⁺ = Aᵀ(AAᵀ + λ²I)⁻¹ = Σ σ_i/(σ_i² + λ²) v_i u_iᵀ with the
// damping switched on only near a singularity, as the smallest singular value σ_d falls below ε:
//
//   λ² = λ0²·(1 − (σ_d/ε)²)  for σ_d < ε,   0 otherwise
//
// and the matching projector I − A_λ⁺A = I − Σ σ_i²/(σ_i² + λ²) v_i v_iᵀ (the same formulas
// with S = P = (G + λ²I)⁻¹, or diag(1/(σ_i² + λ²)) on the Jacobi path). Away from singularities
// (σ_d ≥ ε) it is Compute exactly; at σ_d = 0 the task step along the lost direction is 0
// instead of unbounded. rank() and singular_values() stay those of A.

#include "dpc/control/control_problem.h"
#include "dpc/control/singular_values.h"

namespace dpc {

class TaskPseudoInverse {
 public:
  /// `relative_tolerance`: singular values at or below relative_tolerance·σ_max count as zero.
  explicit TaskPseudoInverse(double relative_tolerance = 1e-12)
      : relative_tolerance_(relative_tolerance) {}

  /// Real-time. Factorizes `a` (1 or 2 rows, at most kMaxControls columns).
  void Compute(const TaskJacobian& a);
  /// Real-time. Factorizes `a` with singularity-robust damping: λ0 = max_damping ≥ 0, ε =
  /// threshold > 0 (see the file comment). damping_squared() tells the λ² used.
  void ComputeDamped(const TaskJacobian& a, double max_damping, double threshold);
  /// λ² of the latest factorization (0 from Compute).
  double damping_squared() const { return damping_squared_; }

  int rank() const { return rank_; }
  /// The singular values (evaluated when read); σ_min is the smallest of the d.
  const SingularValues& singular_values() const { return singular_values_; }
  double sigma_max() const { return singular_values_.max(); }
  double sigma_min() const { return singular_values_.min(); }

  /// Real-time. x = A⁺ e.
  void Solve(const TaskVector& e, ControlVector* x) const;
  /// Real-time. out = (I − A⁺A) v.
  void NullSpaceProjection(const ControlVector& v, ControlVector* out) const;

  /// Real-time. out = step·A⁺e − nullspace_step·(I − A⁺A)φ (paper eq. 10) in one pass:
  /// out = Bᵀ(step·S e + nullspace_step·P B φ) − nullspace_step·φ.
  void GradientProjectionStep(const TaskVector& e, const ControlVector& phi, double step,
                              double nullspace_step, ControlVector* out) const;

 private:
  /// det G above this fraction of (tr G)² takes the normal-equation path.
  static constexpr double kWellConditioned = 1e-6;

  /// Compute (kDamped = false: the paper's code, no damping arithmetic) and ComputeDamped.
  template <bool kDamped>
  void Factorize(const TaskJacobian& a, double max_damping_squared, double threshold_squared);
  /// The one-sided Jacobi factorization; with max_damping_squared > 0 damped as ComputeDamped
  /// (threshold_squared = ε²).
  void ComputeJacobi(const double* r0, const double* r1, double g11, double g22, double g12,
                     double max_damping_squared = 0.0, double threshold_squared = 0.0);

  double relative_tolerance_;
  int rows_ = 1;
  int rank_ = 0;
  int n_ = 0;
  double damping_squared_ = 0.0;
  SingularValues singular_values_;
  double solve_[2][2] = {};    ///< S
  double project_[2][2] = {};  ///< P
  double b_[2][kMaxControls] = {};
};

}  // namespace dpc
