#pragma once
// The control target: a point S* on the Poincaré sphere, or a 1-D set n·S = c (a circle; the
// paper's "special cases", e.g. s3 = 0 for "any linear polarization").
//
//   point  task error ΔS = S* − S_out (paper eq. 5)       distance α = ∠(S_out, S*)
//   set    task error e  = c − n·S_out (scalar)            distance α = |asin(n·S_out) − asin(c)|
//
// The leak through a polarizer aligned with the nearest target point is sin²(α/2); for a point
// this is (1 − S_out·S*)/2.

#include <string>

#include "dpc/optics/stokes.h"

namespace dpc {

class Target {
 public:
  enum class Kind { kPoint, kSet };

  /// Throws std::invalid_argument unless `point` is a finite unit Stokes vector.
  static Target Point(const StokesVector& point);
  /// n·S = offset. `normal` must be finite and non-zero (it is normalized, and the offset with
  /// it); the normalized |offset| must be < 1 so that the set is a circle. Throws otherwise.
  static Target Set(const Vector3& normal, double offset);

  Kind kind() const { return kind_; }
  bool is_point() const { return kind_ == Kind::kPoint; }
  /// The point S* (kPoint), or the point of the set nearest the set's normal direction.
  const StokesVector& point() const { return point_; }
  /// Unit normal n and offset c of a set (normalized).
  const Vector3& normal() const { return normal_; }
  double offset() const { return offset_; }

  /// Angular distance from `s` to the target on the sphere, radians.
  double DistanceRad(const StokesVector& s) const;
  /// Power fraction through a polarizer aligned with the nearest target point: sin²(α/2).
  double LeakFraction(const StokesVector& s) const;
  /// Both at once (real-time). For a point target from the chord c = |S − S*| = 2 sin(α/2):
  /// leak = c²/4 and α = 2 asin(c/2), exact to round-off even for tiny errors (where
  /// (1 − S·S*)/2 cancels); beyond 90° from the supplementary chord |S + S*|.
  void DistanceAndLeak(const StokesVector& s, double* distance_rad, double* leak) const;

  /// "point [0, 0.6, 0.8]" or "set [0, 0, 1]·S = 0".
  std::string Describe() const;

 private:
  Target() = default;
  Kind kind_ = Kind::kPoint;
  StokesVector point_ = StokesVector::UnitX();
  Vector3 normal_ = Vector3::UnitZ();
  double offset_ = 0.0;
};

}  // namespace dpc
