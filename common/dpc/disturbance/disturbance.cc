#include "dpc/disturbance/disturbance.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace dpc {

double SamplePeriodFromRate(double sample_rate_hz, const std::string& who) {
  if (!std::isfinite(sample_rate_hz) || !(sample_rate_hz > 0.0)) {
    throw std::invalid_argument(fmt::format(
        "{}: sample rate {} Hz must be finite and > 0", who, sample_rate_hz));
  }
  return 1.0 / sample_rate_hz;
}

Vector3 NormalizedAxis(const Vector3& axis, const std::string& what) {
  if (!axis.allFinite()) {
    throw std::invalid_argument(fmt::format("{} {} is not finite", what, FormatStokes(axis)));
  }
  const double norm = axis.norm();
  if (norm < 1e-12) {
    throw std::invalid_argument(fmt::format(
        "{} {} has zero length; a rotation needs a direction", what, FormatStokes(axis)));
  }
  return axis / norm;
}

void RequireNonNegativeFinite(double value, const std::string& what) {
  if (!std::isfinite(value) || value < 0.0) {
    throw std::invalid_argument(fmt::format("{} = {} must be finite and >= 0", what, value));
  }
}

}  // namespace dpc
