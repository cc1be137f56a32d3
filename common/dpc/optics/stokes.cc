#include "dpc/optics/stokes.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dpc {

bool IsUnitStokes(const StokesVector& s, double tolerance) {
  return s.allFinite() && std::abs(s.norm() - 1.0) <= tolerance;
}

void RequireUnitStokes(const StokesVector& s, const std::string& what, double tolerance) {
  if (!s.allFinite()) {
    throw std::invalid_argument(
        fmt::format("{}: Stokes vector {} is not finite", what, FormatStokes(s)));
  }
  const double norm = s.norm();
  if (std::abs(norm - 1.0) > tolerance) {
    throw std::invalid_argument(fmt::format(
        "{}: Stokes vector {} has |S| = {:.9g}; a fully polarized state needs |S| = 1 "
        "(tolerance {:g})",
        what, FormatStokes(s), norm, tolerance));
  }
}

double SphereAngleRad(const StokesVector& a, const StokesVector& b) {
  // The chord |a − b| = 2 sin(α/2) is well conditioned for α ≤ π/2; the supplementary chord
  // |a + b| = 2 cos(α/2) is well conditioned for α ≥ π/2.
  const double dot = a.dot(b);
  if (dot >= 0.0) return 2.0 * std::asin(std::min(1.0, 0.5 * (a - b).norm()));
  return M_PI - 2.0 * std::asin(std::min(1.0, 0.5 * (a + b).norm()));
}

std::string FormatStokes(const StokesVector& s) {
  return fmt::format("[{:.6g}, {:.6g}, {:.6g}]", s.x(), s.y(), s.z());
}

}  // namespace dpc
