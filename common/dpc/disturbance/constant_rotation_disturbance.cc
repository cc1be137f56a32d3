#include "dpc/disturbance/constant_rotation_disturbance.h"

#include <fmt/format.h>

#include "dpc/optics/rotation.h"

namespace dpc {

ConstantRotationDisturbance::ConstantRotationDisturbance(double rate_rad_per_s,
                                                         const Vector3& axis,
                                                         double sample_rate_hz)
    : rate_rad_per_s_(rate_rad_per_s), axis_(NormalizedAxis(axis, "constant rotation: axis")) {
  const double sample_period_s = SamplePeriodFromRate(sample_rate_hz, "constant rotation");
  RequireNonNegativeFinite(rate_rad_per_s, "constant rotation: rate_rad_per_s");
  step_rotation_ = RotationAboutAxis(axis_, rate_rad_per_s * sample_period_s);
}

std::string ConstantRotationDisturbance::Describe() const {
  return fmt::format("constant rotation: {:g} rad/s about {}", rate_rad_per_s_,
                     FormatStokes(axis_));
}

}  // namespace dpc
