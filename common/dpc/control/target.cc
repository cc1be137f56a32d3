#include "dpc/control/target.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dpc {

Target Target::Point(const StokesVector& point) {
  RequireUnitStokes(point, "target point");
  Target target;
  target.kind_ = Kind::kPoint;
  target.point_ = point.normalized();
  return target;
}

Target Target::Set(const Vector3& normal, double offset) {
  if (!normal.allFinite() || !std::isfinite(offset)) {
    throw std::invalid_argument(fmt::format("target set: normal {} and offset {} must be finite",
                                            FormatStokes(normal), offset));
  }
  const double norm = normal.norm();
  if (norm < 1e-12) {
    throw std::invalid_argument(
        fmt::format("target set: normal {} has zero length", FormatStokes(normal)));
  }
  const double c = offset / norm;
  if (!(std::abs(c) < 1.0)) {
    throw std::invalid_argument(fmt::format(
        "target set: |offset|/|normal| = {:.6g} must be < 1, or n·S = c has no circle on the "
        "sphere (= 1 is a single point: use a point target)",
        std::abs(c)));
  }
  Target target;
  target.kind_ = Kind::kSet;
  target.normal_ = normal / norm;
  target.offset_ = c;
  // A representative point of the circle: from n towards any perpendicular direction.
  Vector3 e1, e2;
  TangentBasis(target.normal_, &e1, &e2);
  target.point_ = c * target.normal_ + std::sqrt(1.0 - c * c) * e1;
  return target;
}

double Target::DistanceRad(const StokesVector& s) const {
  if (kind_ == Kind::kPoint) return SphereAngleRad(s, point_);
  const double latitude = std::asin(std::clamp(normal_.dot(s), -1.0, 1.0));
  return std::abs(latitude - std::asin(offset_));
}

double Target::LeakFraction(const StokesVector& s) const {
  double distance, leak;
  DistanceAndLeak(s, &distance, &leak);
  return leak;
}

void Target::DistanceAndLeak(const StokesVector& s, double* distance_rad, double* leak) const {
  if (kind_ == Kind::kPoint) {
    const double dx = s[0] - point_[0], dy = s[1] - point_[1], dz = s[2] - point_[2];
    const double chord_squared = dx * dx + dy * dy + dz * dz;  // (2 sin(α/2))²
    if (chord_squared <= 2.0) {
      *leak = 0.25 * chord_squared;
      *distance_rad = 2.0 * std::asin(std::min(1.0, 0.5 * std::sqrt(chord_squared)));
    } else {
      const double ux = s[0] + point_[0], uy = s[1] + point_[1], uz = s[2] + point_[2];
      const double supplementary_squared = ux * ux + uy * uy + uz * uz;  // (2 cos(α/2))²
      *leak = 1.0 - 0.25 * supplementary_squared;
      *distance_rad = M_PI - 2.0 * std::asin(std::min(1.0, 0.5 * std::sqrt(supplementary_squared)));
    }
    return;
  }
  *distance_rad = DistanceRad(s);
  const double sine = std::sin(0.5 * *distance_rad);
  *leak = sine * sine;
}

std::string Target::Describe() const {
  if (kind_ == Kind::kPoint) return "point " + FormatStokes(point_);
  return fmt::format("set {}·S = {:.6g}", FormatStokes(normal_), offset_);
}

}  // namespace dpc
