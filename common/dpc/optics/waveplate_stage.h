#pragma once
// One stage of a dynamic polarization controller: a lossless waveplate whose Mueller matrix
// depends on one or two control signals.
//
//  * Fixed-axis stage: M(φ) = Rot(r, θ(φ)) about a fixed unit axis r (S1, S2, S3 or any
//    vector), θ given by the stage's ControlMap. One control signal. The paper's R1R3R1 and
//    R1R3R1R3 devices are chains of these.
//  * Adjustable-axis stage (paper section II): M = R3(ϕ) R1(θ) R3ᵀ(ϕ), a rotation by the
//    retardance θ about the axis [cos ϕ, sin ϕ, 0] in the S1–S2 plane. θ and ϕ are each either
//    fixed or driven by a control signal through their own map (e.g. a rotatable quarter-wave
//    plate: θ fixed at π/2, ϕ controlled; a LiNbO3 TE–TM converter: both controlled). It is
//    built from the same elemental pieces: three rotations, the outer two sharing ϕ's signal.
//
// A control signal may have a range [min, max] (the device's limits).

#include <optional>
#include <string>
#include <vector>

#include "dpc/optics/control_map.h"
#include "dpc/optics/stokes.h"

namespace dpc {

/// The closed interval a control signal may take. min < max, both finite.
struct ControlRange {
  double min = -1.0;
  double max = 1.0;

  bool Contains(double value) const { return value >= min && value <= max; }
  double Clamp(double value) const { return value < min ? min : (value > max ? max : value); }
};

/// A control signal: its angle map and optional range.
struct ControlChannel {
  std::string name;  ///< e.g. "phi_2" or "wp3.orientation"
  ControlMap map = ControlMap::Linear();
  std::optional<ControlRange> range;
};

/// An angle of an adjustable-axis stage: fixed, or driven by a control signal.
struct StageAngle {
  static StageAngle Fixed(double angle_rad) { return StageAngle{angle_rad, std::nullopt}; }
  static StageAngle Controlled(ControlMap map, std::optional<ControlRange> range = std::nullopt) {
    return StageAngle{0.0, ControlChannel{"", std::move(map), range}};
  }

  double fixed_angle_rad = 0.0;
  std::optional<ControlChannel> control;  ///< set when the angle is driven by a signal
};

class WaveplateStage {
 public:
  enum class Kind { kFixedAxis, kAdjustableAxis };

  /// A fixed-axis stage. `axis` need not be unit length (it is normalized) but must be finite
  /// and non-zero. Throws std::invalid_argument otherwise, or if the range is empty or not
  /// finite.
  static WaveplateStage FixedAxis(const Vector3& axis, ControlMap map = ControlMap::Linear(),
                                  std::optional<ControlRange> range = std::nullopt,
                                  std::string name = "");
  /// R3(ϕ) R1(θ) R3ᵀ(ϕ). Throws if neither angle is controlled, a fixed angle is not finite,
  /// or a range is invalid.
  static WaveplateStage AdjustableAxis(StageAngle retardance, StageAngle orientation,
                                       std::string name = "");

  Kind kind() const { return kind_; }
  const std::string& name() const { return name_; }
  /// Fixed-axis stages: the unit axis.
  const Vector3& axis() const { return axis_; }
  /// Fixed-axis stages: the single control. Adjustable-axis: retardance then orientation,
  /// for those that are controlled.
  const std::vector<ControlChannel>& controls() const { return controls_; }
  const StageAngle& retardance() const { return retardance_; }
  const StageAngle& orientation() const { return orientation_; }

  /// The stage's Mueller matrix for its control values (one per entry of controls()).
  Matrix3 MuellerMatrix(const std::vector<double>& control_values) const;

  /// "R1", "R3", "R[0.6,0.8,0]", "R3(ϕ)R1(θ)R3ᵀ(ϕ)".
  std::string Describe() const;

 private:
  WaveplateStage() = default;

  Kind kind_ = Kind::kFixedAxis;
  std::string name_;
  Vector3 axis_ = Vector3::UnitX();
  StageAngle retardance_;
  StageAngle orientation_;
  std::vector<ControlChannel> controls_;
};

/// Throws std::invalid_argument naming `what` unless min < max and both are finite.
void ValidateControlRange(const ControlRange& range, const std::string& what);

}  // namespace dpc
