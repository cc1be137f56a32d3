#pragma once
// An m-stage waveplate chain and its kinematics (paper section II–III).
//
// Forward kinematics (paper eq. 2):   S_out = f(φ; S_in) = M_m(φ_m) ⋯ M_1(φ_1) S_in.
//
// Closed-form Jacobian (paper eq. 4: J = ∂f/∂φ, 3 × n; its form, eq. 7). Each stage is a
// product of elemental rotations ("elements") e with unit axis r_e and angle θ_e = σ_e·θ_c(φ_c)
// (σ_e = ±1, c the control driving it). With the dynamic-eigenstate rule dM/dθ = [r×] M
// (paper eq. 8):
//
//   ∂S_out/∂θ_e = A_e (r_e × S_e) = (A_e r_e) × S_out,    A_e = M_last ⋯ M_(e+1)
//
// so, by the chain rule (dθ_c/dφ_c is the stage map's derivative: k for θ = k·φ),
//
//   J_c = Ω_c × S_out,   Ω_c = Σ_{e driven by c} σ_e (dθ_c/dφ_c) A_e r_e.
//
// Ω (3 × n) are the stages' axes carried to the output frame, scaled by dθ/dφ ("generators").
// Every column of J is ⊥ S_out, so rank J ≤ 2 whatever m is. For the paper's 3-stage chain
// this is exactly J = [M3M2(r1×S′), M3(r2×S″), r3×S‴] (paper eq. 7).
//
// The same in the input frame: with M = M_last ⋯ M_1 and B_e = M_e ⋯ M_1,
//
//   Mᵀ J_c = Ω′_c × S_in,   Ω′_c = Mᵀ Ω_c = Σ_e σ_e (dθ_c/dφ_c) B_(e−1)ᵀ r_e
//
// (B_eᵀ r_e = B_(e−1)ᵀ r_e because M_e turns about r_e). Evaluate computes M and Ω′ in one
// forward pass over the elements; Ω = M Ω′ and J only when asked for. For an elemental axis,
// B_(e−1)ᵀ r_e is a row of B_(e−1), and M_e B_(e−1) mixes two of its rows.
//
// Real-time use: compute a ChainPose once per command (ComputePose, or ComputePoseFrom for
// small steps from the previous command), then Output / Evaluate with it. None of these
// allocate.

#include <array>
#include <vector>

#include "dpc/optics/rotation.h"
#include "dpc/optics/waveplate_stage.h"

namespace dpc {

/// The most elemental rotations a chain can have (an adjustable-axis stage has three).
inline constexpr int kMaxElements = 3 * kMaxStages;

/// The chain's rotation angles at one control vector φ, with their sines and cosines and the
/// map derivatives dθ/dφ. Fixed-capacity; filled by WaveplateChain::ComputePose.
struct ChainPose {
  ControlVector phi;
  ControlVector dtheta_dphi;  ///< rad per control unit, one per control
  std::array<double, kMaxElements> angle_rad{};
  std::array<double, kMaxElements> cos{};
  std::array<double, kMaxElements> sin{};
  /// Updates by angle addition since the sines and cosines were last evaluated exactly.
  int incremental_steps = 0;
};

/// S_out and the generators at one pose and input; the output-frame generators Ω and the
/// Jacobian J only when Evaluate is asked for them.
struct ChainKinematics {
  StokesVector s_out;
  Matrix3 mueller;            ///< M = M_last ⋯ M_1
  Matrix3X input_generators;  ///< Ω′ = MᵀΩ, 3 × n: MᵀJ_c = Ω′_c × S_in
  Matrix3X generators;        ///< Ω, 3 × n: J_c = Ω_c × S_out (with_jacobian only)
  Matrix3X jacobian;          ///< J = ∂S_out/∂φ, 3 × n (with_jacobian only)
};

class WaveplateChain {
 public:
  /// Throws std::invalid_argument for 0 stages, more than kMaxStages stages, or more than
  /// kMaxControls controls.
  explicit WaveplateChain(std::vector<WaveplateStage> stages);

  /// The paper's devices: one fixed-axis stage per character of `axes` ('1', '2', '3' for S1,
  /// S2, S3), each with θ = rad_per_unit·φ. Stages are listed in the order the light meets them
  /// (stage 1 = M_1 first), so "131" is M = R1R3R1 and "3131" is the paper's M = R1R3R1R3.
  /// Throws for other characters or a length outside 1…kMaxStages.
  static WaveplateChain FromAxes(const std::string& axes, double rad_per_unit = M_PI);

  int stage_count() const { return static_cast<int>(stages_.size()); }
  int control_count() const { return static_cast<int>(controls_.size()); }
  const std::vector<WaveplateStage>& stages() const { return stages_; }
  const std::vector<ControlChannel>& controls() const { return controls_; }
  /// The index of the first control of each stage.
  const std::vector<int>& stage_first_control() const { return stage_first_control_; }

  /// Real-time. Fills `pose` for control vector `phi` (size control_count()).
  void ComputePose(const ControlVector& phi, ChainPose* pose) const;

  /// Real-time. The same pose, derived from `previous` (a pose of this chain; may be `pose`
  /// itself) by angle addition when every element's angle moved by less than 2^-7 rad:
  /// cos(θ+δ) = cos θ cos δ − sin θ sin δ with a short series for δ. That saves the library
  /// sin/cos of successive commands, which differ little. Round-off grows like √steps ulp, so
  /// the sines and cosines are re-evaluated exactly every kMaxIncrementalSteps updates (and on
  /// any larger step): they stay within ~1e-14 of ComputePose's.
  void ComputePoseFrom(const ChainPose& previous, const ControlVector& phi, ChainPose* pose) const;
  static constexpr int kMaxIncrementalSteps = 256;

  /// Real-time. S_out = f(φ; S_in) (paper eq. 2).
  StokesVector Output(const ChainPose& pose, const StokesVector& s_in) const;

  /// Real-time. S_out, M and Ω′ in one forward pass; with_jacobian adds Ω and J (paper eqs. 4, 7).
  void Evaluate(const ChainPose& pose, const StokesVector& s_in, ChainKinematics* out,
                bool with_jacobian = true) const;

  /// The whole chain's Mueller matrix M_m ⋯ M_1.
  Matrix3 MuellerMatrix(const ChainPose& pose) const;

  /// The SOP entering the chain and after each stage: [S_in, S', S'', …, S_out] (m + 1 entries).
  std::vector<StokesVector> StageStates(const ChainPose& pose, const StokesVector& s_in) const;

  // Conveniences (not real-time): compute the pose internally.
  StokesVector Output(const ControlVector& phi, const StokesVector& s_in) const;
  Matrix3X Jacobian(const ControlVector& phi, const StokesVector& s_in) const;

  /// Real-time. Clamps each control with a range into it; returns how many were outside.
  int ClampToRanges(ControlVector* phi) const;
  bool has_ranges() const { return has_ranges_; }
  /// Each control's range limits (−∞ / +∞ for an unbounded control), one per control.
  const std::vector<double>& range_min() const { return range_min_; }
  const std::vector<double>& range_max() const { return range_max_; }

  /// The stages in the order the light meets them: "R3 R1 R3 R1".
  std::string Describe() const;
  /// The paper's notation, the matrix product M = M_m…M_1 (the last stage first):
  /// "R1R3R1R3" for the stages R3 R1 R3 R1 in light order.
  std::string PaperNotation() const;

 private:
  struct Element {
    Vector3 axis;
    ElementalAxis elemental;
    int control;       ///< driving control, or -1 for a fixed angle
    double sign;       ///< θ_e = sign·θ_control
    double fixed_angle_rad;
    bool first_of_control = false;  ///< the first element (in light order) its control drives
  };

  /// θ per control into `theta` and dθ/dφ into pose->dtheta_dphi; copies φ.
  void ComputeAngles(const ControlVector& phi, ChainPose* pose, double* theta) const;

  std::vector<WaveplateStage> stages_;
  std::vector<ControlChannel> controls_;
  std::vector<int> stage_first_control_;
  std::vector<int> stage_end_element_;  ///< one past each stage's last element
  std::vector<Element> elements_;       ///< in the order the light meets them
  bool all_linear_ = true;              ///< every control map is linear (fast path)
  std::vector<double> linear_rad_per_unit_, linear_offset_rad_;
  bool has_ranges_ = false;
  std::vector<double> range_min_, range_max_;  ///< ±∞ for unbounded controls
};

}  // namespace dpc
