#pragma once
// The classical baseline the paper argues against (its reference noe1988): gradient descent on
// the detected power with the gradient estimated by dithering, and control resets.
//
// The law is model-free. It sees only the power leaking through a polarizer aligned with the
// target, P = sin²(α/2) (= (1 − S_out·S*)/2 for a point target), from the measured S_out, and
// runs a cycle:
//   1. for each control i and each sign ±: apply φ = base ± δ e_i, wait `settle_samples`
//      (at least the loop delay, or the detector reads a stale state), read P±_i;
//   2. g_i = (P+_i − P−_i) / (2δ);  base ← base − μ g;
//   3. reset: a control with |base_i| > reset_threshold is wound back by one full turn of its
//      angle (θ ∓ 2π, through the stage map), slewed linearly over `reset_samples` while the
//      others hold; regulation is suspended meanwhile (diagnostics().loop_suspended).
// One gradient takes 2n(settle + 1) samples, during which the input keeps moving: this, and
// the resets, are why dithering cannot track fast SOP changes.
//
// The loop mode does not apply: the law always uses the measured output.

#include "dpc/control/control_law.h"

namespace dpc {

struct DitherSettings {
  double amplitude = 0.02;        ///< δ, control units
  int settle_samples = 50;        ///< wait after each probe before reading (≥ loop delay)
  double reset_threshold = 1.0;   ///< |φ_i| that triggers a reset
  int reset_samples = 50;         ///< duration of one reset
};

class DitheringLaw final : public ControlLaw {
 public:
  /// step μ > 0; amplitude δ > 0; settle_samples ≥ 1; reset_threshold > 0; reset_samples ≥ 1;
  /// all finite. Throws std::invalid_argument otherwise.
  DitheringLaw(double step, const DitherSettings& settings);

  void Activate(const ControlVector& phi) override;
  ControlStatus ComputeUpdate(const ControlProblem& problem, ControlVector* delta_phi) override;
  std::string_view name() const override { return "dither"; }
  bool needs_jacobian() const override { return false; }

 private:
  enum class Phase { kProbe, kReset };

  void StartProbe(int probe);
  /// Starts a reset of the first control beyond the threshold; false if none needs one (or
  /// none can: the map has no full turn inside the control's range).
  bool StartResetIfNeeded(const WaveplateChain& chain);

  double step_;
  DitherSettings settings_;
  Phase phase_ = Phase::kProbe;
  ControlVector base_;
  ControlVector command_;
  ControlVector cost_plus_, cost_minus_;
  int probe_ = 0;  ///< 0 … 2n−1: control probe/2, sign + for even
  int wait_ = 0;
  int reset_control_ = -1;
  double reset_from_ = 0.0, reset_to_ = 0.0;
  int reset_step_ = 0;
};

}  // namespace dpc
