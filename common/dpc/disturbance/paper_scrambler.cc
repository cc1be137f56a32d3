#include "dpc/disturbance/paper_scrambler.h"

#include <cmath>

#include <fmt/format.h>

namespace dpc {

PaperScrambler::PaperScrambler(double rate_rad_per_s, double kick_rms_ratio,
                               const Vector3& rotation_axis, const Vector3& kick_axis,
                               double sample_rate_hz)
    : rate_rad_per_s_(rate_rad_per_s),
      kick_rms_ratio_(kick_rms_ratio),
      rotation_axis_(NormalizedAxis(rotation_axis, "paper scrambler: rotation axis")),
      kick_axis_(NormalizedAxis(kick_axis, "paper scrambler: kick axis")),
      sample_period_s_(SamplePeriodFromRate(sample_rate_hz, "paper scrambler")) {
  RequireNonNegativeFinite(rate_rad_per_s, "paper scrambler: rate_rad_per_s");
  RequireNonNegativeFinite(kick_rms_ratio, "paper scrambler: kick_rms_ratio");
  kick_sigma_rad_ = kick_rms_ratio * rate_rad_per_s * sample_period_s_;
  const double step_rad = rate_rad_per_s * sample_period_s_;
  step_rotation_ = RotationAboutAxis(rotation_axis_, step_rad);
  step_cos_ = std::cos(step_rad);
  step_sin_ = std::sin(step_rad);
  rotation_elemental_ = ClassifyAxis(rotation_axis_);
  kick_elemental_ = ClassifyAxis(kick_axis_);
}

std::string PaperScrambler::Describe() const {
  return fmt::format(
      "paper scrambler: {:g} rad/s about {}, kicks N(0, ({:g} rad)^2) per sample about {} "
      "(kick_rms_ratio {:g})",
      rate_rad_per_s_, FormatStokes(rotation_axis_), kick_sigma_rad_, FormatStokes(kick_axis_),
      kick_rms_ratio_);
}

}  // namespace dpc
