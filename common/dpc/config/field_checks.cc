// The shared field checks of the scenario validation: finite, positive, bounded scalars,
// rotation rates, axes and unit Stokes vectors, each failing with a located ScenarioError.

#include "dpc/config/field_checks.h"

#include <fmt/format.h>

#include <cmath>

#include "dpc/config/scenario_error.h"
#include "dpc/config/scenario_validation.h"

namespace dpc::field_checks {

void Fail(const std::string& path, std::string message) {
  throw ScenarioError(path, std::move(message));
}

std::string FormatVector(const Vector3& v) {
  return fmt::format("[{}, {}, {}]", v.x(), v.y(), v.z());
}

// ---- Scalars.

void RequireFinite(double value, const std::string& path, std::string_view expected) {
  if (!std::isfinite(value)) {
    Fail(path, fmt::format("{} is not a finite number; {}", value, expected));
  }
}

void RequirePositive(double value, const std::string& path, std::string_view expected) {
  RequireFinite(value, path, expected);
  if (!(value > 0.0)) Fail(path, fmt::format("{} is not > 0; {}", value, expected));
}

void RequireNonNegative(double value, const std::string& path, std::string_view expected) {
  RequireFinite(value, path, expected);
  if (value < 0.0) Fail(path, fmt::format("{} is negative; {}", value, expected));
}

void RequireAtMost(double value, double max, const std::string& path, std::string_view what) {
  if (value > max) Fail(path, fmt::format("{} is above {:g}; {} must be at most that", value, max, what));
}

void RequireRate(double rate_rad_per_s, double sample_rate_hz, const std::string& path) {
  RequireFinite(rate_rad_per_s, path, "a rotation rate must be finite and >= 0 rad/s");
  if (rate_rad_per_s < 0.0) {
    Fail(path, fmt::format("{} rad/s is negative; a rotation rate must be >= 0 (use the axis "
                           "direction to reverse)",
                           rate_rad_per_s));
  }
  const double rad_per_sample = rate_rad_per_s / sample_rate_hz;
  if (!(rad_per_sample < M_PI)) {
    Fail(path, fmt::format("{} rad/s at {} Hz: {:.6g} rad per sample exceeds π: the simulation "
                           "cannot resolve it; raise simulation.sample_rate_hz above {:.6g} Hz",
                           rate_rad_per_s, sample_rate_hz, rad_per_sample,
                           rate_rad_per_s / M_PI));
  }
}

// ---- Vectors.

void RequireFiniteVector(const Vector3& v, const std::string& path, std::string_view expected) {
  static constexpr const char* kComponents[3] = {"s1", "s2", "s3"};
  for (int k = 0; k < 3; ++k) RequireFinite(v[k], path + "." + kComponents[k], expected);
}

void RequireAxis(const Vector3& axis, const std::string& path) {
  RequireFiniteVector(axis, path, "an axis component must be finite");
  if (!(axis.norm() >= kMinAxisLength)) {
    Fail(path, fmt::format("zero-length axis {} (|axis| = {:.3g}); an axis needs a direction: "
                           "any vector with |axis| >= {:g} (it is normalized)",
                           FormatVector(axis), axis.norm(), kMinAxisLength));
  }
}

void RequireUnitStokes(const StokesVector& s, const std::string& path) {
  RequireFiniteVector(s, path, "a Stokes component must be finite");
  const double norm = s.norm();
  if (!(std::abs(norm - 1.0) <= kUnitNormTolerance)) {
    Fail(path, fmt::format("{} has |S| = {:.9g}; a fully polarized SOP is a unit Stokes vector "
                           "(|S| within {:g} of 1)",
                           FormatVector(s), norm, kUnitNormTolerance));
  }
}

}  // namespace dpc::field_checks
