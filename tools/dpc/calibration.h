#pragma once
// The arithmetic of `dpc calibrate` (calibrate_command.h), without instruments.
//
// The chain's whole rotation M (S_out = M·S_in) at one setting of the channels is fitted from
// pairs of simultaneous input and output SOPs taken while the input moves (Kabsch: the proper
// rotation closest to the pairs in least squares). Moving one stage i from a reference voltage
// to V turns M into M(V) = A·R_i(θ_i(V))·B, so M(V)·M(ref)ᵀ = A·R_i(θ_i(V) − θ_i(ref))·Aᵀ: a
// rotation by Δθ_i(V) about A·r_i, whatever the other stages' unknown retardances A, B are. Its
// signed angle about that (fixed) axis, unwrapped along the sweep, is the stage's retardance
// relative to the reference. The absolute retardances at the reference (a device's residual
// birefringence at 0 V) come from a least-squares fit of the model chain to every measured M.

#include <optional>
#include <string>
#include <vector>

#include "dpc/optics/stokes.h"

namespace dpc::tools {

/// The proper rotation R minimizing Σ|R·from_k − to_k|² (unit vectors), with the ratio of the
/// middle to the largest singular value of the pairs' cross-covariance in `spread` (near 0: the
/// inputs were collinear and the rotation is not determined). Throws std::invalid_argument for
/// fewer than 2 pairs or sizes that differ.
Matrix3 FitRotation(const std::vector<StokesVector>& from, const std::vector<StokesVector>& to, double* spread);

/// The rotation axis of R (unit; its sign arbitrary) and |angle|; nullopt if R is within
/// `min_angle_rad` of the identity or of a half turn (no stable axis there).
std::optional<Vector3> RotationAxis(const Matrix3& rotation, double min_angle_rad = 0.2);

/// The signed angle of R about `axis` (unit), in (−π, π]: R ≈ Rot(axis, angle).
double SignedAngleAbout(const Matrix3& rotation, const Vector3& axis);

/// `angles_rad` made continuous (consecutive steps of less than π), in place.
void Unwrap(std::vector<double>* angles_rad);

/// A polynomial in the scaled variable u = (x − centre)/half (well conditioned over the range).
struct ScaledPolynomial {
  std::vector<double> coefficients;  ///< of u, c_0 first
  double centre = 0.0, half = 1.0;
  double operator()(double x) const;
  /// d/dx.
  double Derivative(double x) const;
};

/// The least-squares polynomial of `degree` through (x_k, y_k); throws std::invalid_argument
/// with fewer points than coefficients.
ScaledPolynomial FitPolynomial(const std::vector<double>& x, const std::vector<double>& y, int degree);

}  // namespace dpc::tools
