#pragma once
// Gradient projection (paper section III.B, eqs. 9–10), the reset-free endless control law:
//
//   Δφ = μ J⁺ ΔS − μ_N (I − J⁺J) ∇H(φ),      H = ½‖φ‖² (the paper): ∇H = φ
//
// The task term (step μ) drives S_out to the target; the null-space term (step μ_N) moves φ
// towards the minimum of H among the controls that give the same S_out, so φ stays bounded
// while the input SOP rotates without end. (The paper writes the null-space term with "+μ" in
// the text and "−" in eqs. 9–10; it must be "−" to decrease H, as the equations have it.)
//
// Thresholded variant (paper Fig. 5, "gpt"): the null-space term runs only while some
// |φ_i| > threshold; diagnostics().nullspace_active tells when it ran.
//
// Options beyond the paper (GradientProjectionOptions):
//
//   Singularity-robust damping (max_damping λ0 > 0, damping_threshold ε): J⁺ and I − J⁺J are
//   replaced by the damped J_λ⁺ = Jᵀ(JJᵀ + λ²I)⁻¹ and I − J_λ⁺J with λ² = λ0²(1 − (σ_min/ε)²)
//   below σ_min = ε, 0 above (task_pseudo_inverse.h): near a singularity the task step along
//   the vanishing direction stays bounded instead of growing like 1/σ_min.
//
//   Range-aware null space (range_aware): for a control with range [lo, hi], centre c and half
//   width h, x = (φ − c)/h and
//       H = Σ_i h_i²(x_i²/2 + x_i⁸/8),   ∂H/∂φ_i = h_i·clip(x_i + x_i⁷, ±kMaxRangeGradient)
//   (½φ² for a control without a range): the paper's ½‖φ‖² near the centre (∂H/∂φ_i ≈ φ_i − c_i,
//   in the controls' own unit, so μ_N means the same with and without the criterion whether φ
//   is in units of π rad or in volts), pushing harder towards the inside near an end.
//   Then saturate and re-solve: if φ + Δφ leaves a range, that control is fixed at its limit
//   (Δφ_i = limit − φ_i) and the task is solved again with the other controls only, the fixed
//   ones' contribution moved to the task side,
//       Δφ_F = μ J_F⁺(e − J_S Δφ_S/μ) − μ_N (I − J_F⁺J_F) ∇H_F,
//   repeated while another control would leave its range (at most n times). The re-solve is
//   always damped (with λ0, ε, or the defaults when damping is off): with one control fixed, a
//   3-stage chain has no redundancy left and may sit at a singularity. Every command then stays
//   inside the ranges without the integrator's clamp.
//
//   Curvature correction (curvature_correction): the step Δφ is computed from the linear model;
//   along a fast reconfiguration (near a singularity, or a large null-space step) the chain's
//   curvature leaves a residual r = TΔφ − (e(φ) − e(φ + Δφ)), the decrease of the task error the
//   linear model promised minus the one the model gives. One correction step Δφ += J_λ⁺r (always
//   damped: with λ0, ε, or the defaults when damping is off; one extra pose and chain pass)
//   removes it to second order. With
//   delay compensation (delay_compensator.h) whatever residual is left is corrected only at the
//   integrator's rate μ, so this is what lets a deterministic rotation be tracked exactly.
//
// J⁺ and I − J⁺J come from the closed-form reduced-task pseudo-inverse (task_pseudo_inverse.h):
// about 100 flops for 4 stages, no SVD, no allocation. The plain law (no option) runs exactly
// the paper's code path.

#include <optional>

#include "dpc/control/control_law.h"
#include "dpc/control/task_pseudo_inverse.h"

namespace dpc {

struct GradientProjectionOptions {
  std::optional<double> threshold;          ///< gpt: |φ_i| above which the null space runs
  double singular_value_tolerance = 1e-12;  ///< relative, for J⁺
  double max_damping = 0.0;                 ///< λ0; 0: no damping
  double damping_threshold = 0.5;           ///< ε: damping starts below σ_min = ε
  bool range_aware = false;                 ///< range criterion + saturate and re-solve
  bool curvature_correction = false;        ///< one correction step for the curvature
};

class GradientProjectionLaw final : public ControlLaw {
 public:
  /// Clip of the range criterion's gradient x + x⁷ (reached at |x| ≈ 1.17, outside the range).
  static constexpr double kMaxRangeGradient = 4.0;
  /// The re-solve's and the correction's damping when damping is off.
  static constexpr double kDefaultMaxDamping = 0.25;
  static constexpr double kDefaultDampingThreshold = 0.5;

  /// step μ > 0, nullspace_step μ_N ≥ 0, both finite; threshold (if set) finite and ≥ 0.
  /// Throws std::invalid_argument otherwise.
  GradientProjectionLaw(double step, double nullspace_step,
                        std::optional<double> threshold = std::nullopt,
                        double singular_value_tolerance = 1e-12);
  /// The same with the options; max_damping ≥ 0 and damping_threshold > 0, finite. Throws
  /// std::invalid_argument otherwise.
  GradientProjectionLaw(double step, double nullspace_step,
                        const GradientProjectionOptions& options);

  ControlStatus ComputeUpdate(const ControlProblem& problem, ControlVector* delta_phi) override;
  std::string_view name() const override { return threshold_ ? "gpt" : "gp"; }
  bool needs_jacobian() const override { return false; }

  /// λ² of the latest update's (first) factorization.
  double damping_squared() const { return pseudo_inverse_.damping_squared(); }
  /// Controls fixed at a range limit by the latest update (range_aware).
  int saturated_controls() const { return saturated_count_; }

 private:
  /// The update with any of the options (ComputeUpdate runs the paper's law without them).
  ControlStatus ComputeUpdateWithOptions(const ControlProblem& problem, ControlVector* delta_phi);
  /// Whether the null-space term runs at φ (μ_N > 0; gpt: some |φ_i| > threshold).
  bool NullspaceActive(const ControlVector& phi) const;
  void Factorize(const TaskJacobian& task);
  /// ∇H at φ into gradient_ (range criterion).
  void RangeGradient(const ControlProblem& problem);
  /// Saturate and re-solve (range_aware); `nullspace_step` as used for the first solve.
  void SaturateAndResolve(const ControlProblem& problem, double nullspace_step,
                          ControlVector* delta_phi);
  /// The curvature correction of Δφ (with the current factorization).
  void CorrectCurvature(const ControlProblem& problem, ControlVector* delta_phi);

  double step_;
  double nullspace_step_;
  std::optional<double> threshold_;
  double max_damping_ = 0.0;
  double damping_threshold_ = kDefaultDampingThreshold;
  bool range_aware_ = false;
  bool curvature_correction_ = false;
  bool has_options_ = false;
  TaskPseudoInverse pseudo_inverse_;
  ChainPose next_pose_;
  ControlVector next_phi_, correction_;
  TaskVector residual_;
  // Scratch (range_aware), sized at first use within fixed capacity.
  ControlVector gradient_, fixed_delta_, masked_gradient_;
  TaskJacobian masked_task_;
  TaskVector shifted_error_;
  bool saturated_[kMaxControls] = {};
  int saturated_count_ = 0;
};

}  // namespace dpc
