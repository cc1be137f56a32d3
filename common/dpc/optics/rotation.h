#pragma once
// Rotations of the Poincaré sphere: the Mueller matrices of lossless waveplates.
//
// Elemental rotations by θ about S1, S2, S3, right-hand rule (paper, section II):
//
//        | 1   0    0  |         |  c  0  s |         | c  -s  0 |
//   R1 = | 0   c   -s  |    R2 = |  0  1  0 |    R3 = | s   c  0 |      c = cos θ, s = sin θ
//        | 0   s    c  |         | -s  0  c |         | 0   0  1 |
//
// Rotation about any unit axis r (paper eq. 1, Rodrigues):
//   M = I + sin θ [r×] + (1 − cos θ) [r×]²,  with [r×] the cross-product matrix of r.

#include <cmath>

#include "dpc/optics/stokes.h"

namespace dpc {

/// The elemental axes S1, S2, S3; kGeneral marks any other unit axis.
enum class ElementalAxis : int { kGeneral = 0, kS1 = 1, kS2 = 2, kS3 = 3 };

/// The unit vector of an elemental axis (S1 = [1,0,0], …). Throws for kGeneral.
Vector3 ElementalAxisVector(ElementalAxis axis);

/// Which elemental axis `axis` is (exactly), or kGeneral.
ElementalAxis ClassifyAxis(const Vector3& axis);

/// [r×]: the matrix with [r×] v = r × v.
Matrix3 CrossProductMatrix(const Vector3& r);

/// Paper eq. 1: the rotation by `angle_rad` about the unit axis `axis` (right-hand rule).
Matrix3 RotationAboutAxis(const Vector3& axis, double angle_rad);
/// The same from a precomputed cosine and sine of the angle.
Matrix3 RotationAboutAxis(const Vector3& axis, double cos_angle, double sin_angle);

Matrix3 R1(double angle_rad);
Matrix3 R2(double angle_rad);
Matrix3 R3(double angle_rad);

/// Rotates `v` by the angle with cosine `c` and sine `s` about the unit `axis` (Rodrigues on a
/// vector, ~15 flops): v cos θ + (r × v) sin θ + r (r·v)(1 − cos θ).
inline Vector3 RotateVector(const Vector3& axis, double c, double s, const Vector3& v) {
  return c * v + s * axis.cross(v) + ((1.0 - c) * axis.dot(v)) * axis;
}

/// Rotates (x, y, z) by the angle with cosine `c` and sine `s` about an elemental axis (the
/// other two components turn in their plane; ~6 flops). Does nothing for kGeneral. T: double, or
/// a vector of doubles (the batched simulator's lanes, sim/batch_kernel_impl.h).
template <typename T>
inline void RotateElemental(ElementalAxis axis, T c, T s, T& x, T& y, T& z) {
  T t;
  switch (axis) {
    case ElementalAxis::kS1: t = y; y = c * t - s * z; z = s * t + c * z; return;
    case ElementalAxis::kS2: t = z; z = c * t - s * x; x = s * t + c * x; return;
    case ElementalAxis::kS3: t = x; x = c * t - s * y; y = s * t + c * y; return;
    case ElementalAxis::kGeneral: return;
  }
}

/// The bound below which SmallAngleSinCos is exact to about 1 ulp: 2^-7 rad.
inline constexpr double kSmallAngleLimit = 0.0078125;

/// sin and cos of |x| < kSmallAngleLimit by their Taylor series (no branch, ~12 flops).
/// Truncation: x^9/9! < 1e-24 ≈ 1e-22·|x| and x^8/8! < 4e-22 for |x| < 2^-7, far below 1 ulp.
/// T: double, or a vector of doubles (the batched simulator's lanes, sim/batch_kernel_impl.h).
template <typename T>
inline void SmallAngleSinCos(T x, T* s, T* c) {
  const T x2 = x * x;
  *s = x * (1.0 + x2 * (-1.0 / 6 + x2 * (1.0 / 120 + x2 * (-1.0 / 5040))));
  *c = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24 + x2 * (-1.0 / 720)));
}

/// a·b + c with one rounding where the target has fused multiply-add (x86-64-v3, the default
/// build), else with two. The build keeps -ffp-contract=off, so the compiler never fuses behind
/// the source's back (the same expression gives the same bits wherever it is inlined, and the
/// compensated sums stay exact); the fused control update (control/fused_gradient_projection.h)
/// asks for a fused multiply-add explicitly where one shortens its dependency chain: on the
/// development VM's Zen 5 a multiply feeding an add takes 6 cycles, a fused multiply-add 4.
/// The same build gives the same bits on every run; a build without FMA (-DDPC_X86_64_V3=OFF)
/// rounds these twice and so differs from the default build in the last bits of such results.
#ifdef __FMA__
inline constexpr bool kMulAddIsFused = true;
#else
inline constexpr bool kMulAddIsFused = false;
#endif
[[gnu::always_inline]] inline double MulAdd(double a, double b, double c) {
  if constexpr (kMulAddIsFused) {
    return std::fma(a, b, c);
  } else {
    return a * b + c;
  }
}

/// cos(θ + x) and sin(θ + x) from c = cos θ, s = sin θ for |x| < kSmallAngleLimit: the angle
/// addition with sin x and cos x by the series of SmallAngleSinCos, arranged for a short
/// dependency chain from x (a command's new pose from its step): the series in x² by Estrin's
/// scheme (x⁴ beside the pairs of terms), sin x = x·(…) with x multiplied into s and c while the
/// series runs, then one product and one multiply-add. mul_add(a, b, c) is a·b + c (MulAdd, or
/// the batched simulator's); T is double, Lanes or a vector of doubles. Within ~1 ulp of the
/// angle addition with the library's sine and cosine of x (rotation_test).
template <typename T, typename MulAddFn>
[[gnu::always_inline]] inline void SmallAngleTurn(T c, T s, T x, MulAddFn mul_add, T* c_next,
                                                  T* s_next) {
  const T zero{};
  const auto k = [&](double value) -> T { return zero + value; };
  const T x2 = x * x, x4 = x2 * x2;
  const T sin_x_over_x = mul_add(x4, mul_add(x2, k(-1.0 / 5040), k(1.0 / 120)),
                                 mul_add(x2, k(-1.0 / 6), k(1.0)));
  const T cos_x = mul_add(x4, mul_add(x2, k(-1.0 / 720), k(1.0 / 24)),
                          mul_add(x2, k(-0.5), k(1.0)));
  const T s_x = s * x, c_x = c * x;
  *c_next = mul_add(c, cos_x, -(s_x * sin_x_over_x));
  *s_next = mul_add(s, cos_x, c_x * sin_x_over_x);
}

/// The bound below which SmallArcSine is exact to about 1 ulp.
inline constexpr double kSmallArcSineLimit = 0.18;

/// asin(x) for |x| ≤ kSmallArcSineLimit by its Taylor series Σ (2n)!/(4ⁿ(n!)²(2n+1))·x^(2n+1),
/// to x²³ (truncation < 0.18²⁵·0.0061 ≈ 1e-21, far below 1 ulp of the result; rotation_test
/// checks the relative error against std::asin). Branch-free, so a loop over it vectorizes,
/// which the library call does not. For a locked output (errors below ~20°) this is what the statistics hit.
inline double SmallArcSine(double x) {
  const double z = x * x;
  double p = 88179.0 / 12058624.0;
  p = p * z + 46189.0 / 5505024.0;
  p = p * z + 12155.0 / 1245184.0;
  p = p * z + 6435.0 / 557056.0;
  p = p * z + 143.0 / 10240.0;
  p = p * z + 231.0 / 13312.0;
  p = p * z + 63.0 / 2816.0;
  p = p * z + 35.0 / 1152.0;
  p = p * z + 5.0 / 112.0;
  p = p * z + 3.0 / 40.0;
  p = p * z + 1.0 / 6.0;
  p = p * z + 1.0;
  return x * p;
}

/// sin and cos of an angle; the series for |x| < 2^-7 (what small per-sample steps hit), a few
/// multiplications instead of the library call.
inline void SinCos(double x, double* s, double* c) {
  if (x > -kSmallAngleLimit && x < kSmallAngleLimit) {
    SmallAngleSinCos(x, s, c);
    return;
  }
  *s = std::sin(x);  // GCC merges the pair into one sincos call
  *c = std::cos(x);
}

}  // namespace dpc
