#pragma once
// The map from a stage's control signal φ (device units) to its rotation angle θ (radians).
//
// The paper uses the linear map θ = π·φ ("one unit of control signal generates π phase
// shift"). Real devices are calibrated: a polynomial fit, or a measured lookup table. The
// Jacobian needs dθ/dφ (the chain rule: ∂S_out/∂φ_i = (dθ_i/dφ_i)·∂S_out/∂θ_i).
//
//   linear       θ = k·φ + θ0                      dθ/dφ = k                 (default k = π)
//   polynomial   θ = Σ_j c_j φ^j                   dθ/dφ = Σ_j j·c_j φ^(j−1)
//   table        piecewise-linear through measured (φ_j, θ_j), φ strictly increasing and θ
//                strictly monotonic; extrapolated linearly beyond the ends. A table has no
//                analytic derivative: dθ/dφ is a central difference of the interpolant, with
//                a step far below the knot spacing (the segment slope away from knots, the
//                mean of the two slopes at a knot).

#include <optional>
#include <string>
#include <vector>

namespace dpc {

class ControlMap {
 public:
  enum class Kind { kLinear, kPolynomial, kTable };

  /// The most polynomial coefficients (degree 15) and table points accepted.
  static constexpr int kMaxPolynomialCoefficients = 16;
  static constexpr int kMaxTablePoints = 4096;

  /// θ = rad_per_unit·φ + offset_rad. Throws std::invalid_argument if rad_per_unit is zero or
  /// either value is not finite.
  static ControlMap Linear(double rad_per_unit = 3.141592653589793, double offset_rad = 0.0);
  /// θ = Σ_j coefficients_rad[j]·φ^j. Throws if empty, longer than kMaxPolynomialCoefficients,
  /// not finite, or constant (all coefficients of degree ≥ 1 zero).
  static ControlMap Polynomial(std::vector<double> coefficients_rad);
  /// Piecewise-linear through (control[j], angle_rad[j]). Throws if the sizes differ, there are
  /// fewer than 2 or more than kMaxTablePoints points, a value is not finite, control is not
  /// strictly increasing, or angle_rad is not strictly monotonic. Messages name the index.
  static ControlMap Table(std::vector<double> control, std::vector<double> angle_rad);

  Kind kind() const { return kind_; }
  /// θ(φ), radians.
  double AngleRad(double control) const;
  /// dθ/dφ at φ (analytic, or the central difference for tables).
  double DerivativeRadPerUnit(double control) const;
  bool has_analytic_derivative() const { return kind_ != Kind::kTable; }
  /// For the linear map: k (rad per unit).
  double linear_rad_per_unit() const { return linear_rad_per_unit_; }

  /// A φ in [lo, hi] with θ(φ) = angle_rad, if θ is monotonic over [lo, hi] and the angle is
  /// reached there (bisection for non-linear maps); otherwise nullopt.
  std::optional<double> ControlForAngle(double angle_rad, double lo, double hi) const;

  /// The control span of a table, [first, last] point; nullopt for other kinds.
  std::optional<std::pair<double, double>> TableSpan() const;

  /// "linear 3.14159 rad/unit", "polynomial degree 3", "table 12 points".
  std::string Describe() const;

 private:
  ControlMap() = default;
  double TableAngle(double control) const;

  Kind kind_ = Kind::kLinear;
  double linear_rad_per_unit_ = 0.0;
  double linear_offset_rad_ = 0.0;
  std::vector<double> coefficients_rad_;
  std::vector<double> table_control_;
  std::vector<double> table_angle_rad_;
  double table_difference_step_ = 0.0;
};

}  // namespace dpc
