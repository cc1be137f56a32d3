#pragma once
// Gradient projection (paper section III.B, eq. 12), the reset-free endless control law:
//
//   Δφ = μ J⁺ ΔS − μ_N (I − J⁺J) φ
//
// The task term (step μ) drives S_out to the target; the null-space term (step μ_N) moves φ
// towards the minimum ‖φ‖² among the controls that give the same S_out, so φ stays bounded
// while the input SOP rotates without end. (The paper writes the null-space term with "+μ" in
// the text and "−" in eq. 12; it must be "−" to decrease ‖φ‖², as eq. 12 has it.)
//
// Thresholded variant (paper Fig. 5, "gpt"): the null-space term runs only while some
// |φ_i| > threshold; diagnostics().nullspace_active tells when it ran.
//
// J⁺ and I − J⁺J come from the closed-form reduced-task pseudo-inverse (task_pseudo_inverse.h):
// about 100 flops for 4 stages, no SVD, no allocation.

#include <optional>

#include "dpc/control/control_law.h"
#include "dpc/control/task_pseudo_inverse.h"

namespace dpc {

class GradientProjectionLaw final : public ControlLaw {
 public:
  /// step μ > 0, nullspace_step μ_N ≥ 0, both finite; threshold (if set) finite and ≥ 0.
  /// Throws std::invalid_argument otherwise.
  GradientProjectionLaw(double step, double nullspace_step,
                        std::optional<double> threshold = std::nullopt,
                        double singular_value_tolerance = 1e-12);

  ControlStatus ComputeUpdate(const ControlProblem& problem, ControlVector* delta_phi) override;
  std::string_view name() const override { return threshold_ ? "gpt" : "gp"; }
  bool needs_jacobian() const override { return false; }

 private:
  double step_;
  double nullspace_step_;
  std::optional<double> threshold_;
  TaskPseudoInverse pseudo_inverse_;
};

}  // namespace dpc
