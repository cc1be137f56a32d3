#pragma once
// Stokes vectors on the Poincaré sphere and the fixed-capacity linear-algebra types of the core.
//
// A fully polarized state of polarization (SOP) is a unit Stokes vector S = [s1, s2, s3]^T,
// s1² + s2² + s3² = 1 (paper, section II). Every type here has a compile-time capacity so that
// the real-time paths never touch the heap.

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <cmath>
#include <string>

namespace dpc {

/// The most waveplate stages a chain may have.
inline constexpr int kMaxStages = 16;
/// The most control signals a chain may have: an adjustable-axis stage has up to two.
inline constexpr int kMaxControls = 2 * kMaxStages;

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;
/// A Stokes vector [s1, s2, s3]; unit length for a fully polarized SOP.
using StokesVector = Eigen::Vector3d;
/// The control signals φ = [φ1 … φn]^T (device units, e.g. normalized volts).
using ControlVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxControls, 1>;
/// A 3 × n matrix, one column per control signal (the Jacobian J and the generators Ω).
using Matrix3X = Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxControls>;

/// Tolerance on |S| − 1 for a vector to count as a unit Stokes vector.
inline constexpr double kUnitNormTolerance = 1e-6;

/// True when every component of `v` is finite.
inline bool AllFinite(const Eigen::Ref<const Eigen::VectorXd>& v) { return v.allFinite(); }

/// True when `s` is finite and |s| is within `tolerance` of 1.
bool IsUnitStokes(const StokesVector& s, double tolerance = kUnitNormTolerance);

/// Throws std::invalid_argument naming `what` unless `s` is a finite unit Stokes vector.
void RequireUnitStokes(const StokesVector& s, const std::string& what,
                       double tolerance = kUnitNormTolerance);

/// The angle between two unit Stokes vectors on the Poincaré sphere, in radians, [0, π].
/// Accurate near 0 and near π (uses half-chord lengths, not acos of the dot product).
double SphereAngleRad(const StokesVector& a, const StokesVector& b);

/// Leak through a polarizer aligned with `target`: (1 − S·S*)/2, in [0, 1] (power fraction).
inline double PolarizerLeak(const StokesVector& s, const StokesVector& target) {
  return 0.5 * (1.0 - s.dot(target));
}

/// Brings a nearly unit vector back to unit length with one Newton step (no square root):
/// s ← s·(3 − |s|²)/2. Exact to second order in (|s|² − 1); used to stop round-off drift.
inline void RenormalizeNearUnit(StokesVector* s) { *s *= 0.5 * (3.0 - s->squaredNorm()); }

/// A right-handed orthonormal basis (e1, e2) of the tangent plane at unit `s`:
/// e1 × e2 = s. Branch-free, no square root (Duff et al., JCGT 6(1), 2017). Real-time.
inline void TangentBasis(const StokesVector& s, Vector3* e1, Vector3* e2) {
  const double sign = std::copysign(1.0, s.z());
  const double a = -1.0 / (sign + s.z());
  const double b = s.x() * s.y() * a;
  *e1 = Vector3(1.0 + sign * s.x() * s.x() * a, sign * b, -sign * s.x());
  *e2 = Vector3(b, sign + s.y() * s.y() * a, -s.y());
}

/// "[0.000, 0.600, 0.800]".
std::string FormatStokes(const StokesVector& s);

}  // namespace dpc
