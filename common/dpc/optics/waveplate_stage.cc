#include "dpc/optics/waveplate_stage.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "dpc/optics/rotation.h"

namespace dpc {

void ValidateControlRange(const ControlRange& range, const std::string& what) {
  if (!std::isfinite(range.min) || !std::isfinite(range.max)) {
    throw std::invalid_argument(
        fmt::format("{}: range [{}, {}] is not finite", what, range.min, range.max));
  }
  if (!(range.min < range.max)) {
    throw std::invalid_argument(
        fmt::format("{}: range [{}, {}] is empty (min must be < max)", what, range.min, range.max));
  }
}

WaveplateStage WaveplateStage::FixedAxis(const Vector3& axis, ControlMap map,
                                         std::optional<ControlRange> range, std::string name) {
  if (!axis.allFinite()) {
    throw std::invalid_argument(fmt::format("stage axis {} is not finite", FormatStokes(axis)));
  }
  const double norm = axis.norm();
  if (norm < 1e-12) {
    throw std::invalid_argument(
        fmt::format("stage axis {} has zero length; a rotation needs a direction",
                    FormatStokes(axis)));
  }
  if (range) ValidateControlRange(*range, "stage control");
  WaveplateStage stage;
  stage.kind_ = Kind::kFixedAxis;
  stage.name_ = std::move(name);
  stage.axis_ = axis / norm;
  stage.controls_.push_back(ControlChannel{"", std::move(map), range});
  return stage;
}

WaveplateStage WaveplateStage::AdjustableAxis(StageAngle retardance, StageAngle orientation,
                                              std::string name) {
  if (!retardance.control && !orientation.control) {
    throw std::invalid_argument(
        "adjustable-axis stage: neither the retardance nor the orientation is controlled");
  }
  for (const auto* angle : {&retardance, &orientation}) {
    const char* which = angle == &retardance ? "retardance" : "orientation";
    if (angle->control) {
      if (angle->control->range) {
        ValidateControlRange(*angle->control->range,
                             fmt::format("adjustable-axis stage {}", which));
      }
    } else if (!std::isfinite(angle->fixed_angle_rad)) {
      throw std::invalid_argument(fmt::format(
          "adjustable-axis stage: fixed {} {} is not finite", which, angle->fixed_angle_rad));
    }
  }
  WaveplateStage stage;
  stage.kind_ = Kind::kAdjustableAxis;
  stage.name_ = std::move(name);
  stage.retardance_ = std::move(retardance);
  stage.orientation_ = std::move(orientation);
  if (stage.retardance_.control) stage.controls_.push_back(*stage.retardance_.control);
  if (stage.orientation_.control) stage.controls_.push_back(*stage.orientation_.control);
  return stage;
}

Matrix3 WaveplateStage::MuellerMatrix(const std::vector<double>& control_values) const {
  if (control_values.size() != controls_.size()) {
    throw std::invalid_argument(fmt::format("stage {} has {} control(s), {} value(s) given",
                                            Describe(), controls_.size(), control_values.size()));
  }
  if (kind_ == Kind::kFixedAxis) {
    return RotationAboutAxis(axis_, controls_[0].map.AngleRad(control_values[0]));
  }
  const size_t orientation_index = retardance_.control ? 1 : 0;
  const double theta = retardance_.control ? controls_[0].map.AngleRad(control_values[0])
                                           : retardance_.fixed_angle_rad;
  const double phi =
      orientation_.control
          ? controls_[orientation_index].map.AngleRad(control_values[orientation_index])
          : orientation_.fixed_angle_rad;
  return R3(phi) * R1(theta) * R3(phi).transpose();
}

std::string WaveplateStage::Describe() const {
  if (kind_ == Kind::kAdjustableAxis) return "R3(ϕ)R1(θ)R3ᵀ(ϕ)";
  switch (ClassifyAxis(axis_)) {
    case ElementalAxis::kS1: return "R1";
    case ElementalAxis::kS2: return "R2";
    case ElementalAxis::kS3: return "R3";
    case ElementalAxis::kGeneral: break;
  }
  return fmt::format("R[{:.4g},{:.4g},{:.4g}]", axis_.x(), axis_.y(), axis_.z());
}

}  // namespace dpc
