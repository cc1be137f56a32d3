#pragma once
// Four doubles processed together: one AVX register on x86-64-v3 (the compiler splits the
// operations in two for narrower targets). The fused control update works on 3 or 4 controls;
// its per-control arithmetic (Δφ, the angle steps, their sines and cosines, the new pose) is
// written on Lanes rather than left to the auto-vectorizer, which gives up on that kernel's
// branches and leaves ~60 scalar instructions where ~15 vector ones do.
//
// Lanes is the GCC/Clang vector extension: +, −, ·, comparisons and a[i] work lane by lane,
// a scalar operand is broadcast.

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>

#if defined(__AVX__) && defined(__FMA__)
#include <immintrin.h>
#endif

#include "dpc/optics/rotation.h"

// Lanes are passed by value only between always-inlined functions; GCC's note that an AVX
// vector's calling convention differs without AVX (-Wpsabi, builds without x86-64-v3) concerns
// calls that never happen.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace dpc {

using Lanes = double __attribute__((vector_size(32)));

/// x in every lane.
[[gnu::always_inline]] inline Lanes Splat(double x) { return Lanes{x, x, x, x}; }

/// The lanes as an array (e.g. for code that takes const double*).
[[gnu::always_inline]] inline std::array<double, 4> ToArray(Lanes x) {
  return std::bit_cast<std::array<double, 4>>(x);
}

/// a·b + c lane by lane, rounded once where the target has FMA (see the scalar MulAdd).
[[gnu::always_inline]] inline Lanes MulAdd(Lanes a, Lanes b, Lanes c) {
#if defined(__AVX__) && defined(__FMA__)
  return _mm256_fmadd_pd(a, b, c);
#else
  return a * b + c;
#endif
}

/// |x| lane by lane.
[[gnu::always_inline]] inline Lanes Abs(Lanes x) {
  using Bits = int64_t __attribute__((vector_size(32)));
  return std::bit_cast<Lanes>(std::bit_cast<Bits>(x) & INT64_MAX);
}

/// The largest lane (of lanes that are not NaN; a NaN lane may make it NaN).
[[gnu::always_inline]] inline double MaxLane(Lanes x) {
  const double a = x[0] > x[1] ? x[0] : x[1], b = x[2] > x[3] ? x[2] : x[3];
  return a > b ? a : b;
}

/// The sum of the lanes, (x0 + x1) + (x2 + x3).
[[gnu::always_inline]] inline double SumLanes(Lanes x) { return (x[0] + x[1]) + (x[2] + x[3]); }

/// Beyond this |angle| SinCos takes the library: n·pio2_1 below is exact only for |n| < 2²⁰.
inline constexpr double kLanesSinCosLimit = 1.6e6;  // < 2²⁰·π/2

/// sin and cos of x lane by lane, within ~2 ulp of the library's (lanes_test measures it),
/// without a call or a branch for |x| < kLanesSinCosLimit (a chain of ~16 ns from x to both on
/// the development VM, where the library's sin alone takes about as long for one angle); lanes
/// beyond (or NaN, ±Inf) by the library.
/// fdlibm's method (Sun Microsystems, 1993): x is reduced by the nearest multiple n of π/2,
/// π/2 split as fdlibm's pio2_1 (33 bits, so that n·pio2_1 is exact for |n| < 2²⁰) + pio2_1t;
/// then fdlibm's minimax kernels __kernel_sin and __kernel_cos (|error| < 2⁻⁵⁸ on
/// [−π/4, π/4]), their polynomials evaluated in Estrin's scheme (a shorter dependency chain than
/// Horner's) with MulAdd, and the quadrant n mod 4 picks and signs the results.
[[gnu::always_inline]] inline void SinCos(Lanes x, Lanes* s, Lanes* c) {
  using Mask = int64_t __attribute__((vector_size(32)));
  // n = nearest integer to x·2/π (|x·2/π| < 2⁵¹: adding 1.5·2⁵² rounds to an integer).
  constexpr double kRound = 0x1.8p52;
  const Lanes shifted = MulAdd(x, Splat(0x1.45f306dc9c883p-1), Splat(kRound));  // 2/π
  const Lanes n = shifted - kRound;
  const Mask quadrant = std::bit_cast<Mask>(shifted) & 3;  // n mod 4 (the mantissa's low bits)
  // y = x − n·π/2: the pio2_1 part is exact, the pio2_1t part rounds once more.
  const Lanes r = MulAdd(-n, Splat(0x1.921fb544p0), x);         // fdlibm pio2_1
  const Lanes y = MulAdd(-n, Splat(0x1.0b4611a626331p-34), r);  // fdlibm pio2_1t
  // fdlibm's kernels on |y| ≤ π/4.
  const Lanes z = y * y;
  const Lanes z2 = z * z;
  const Lanes v = z * y;
  const Lanes s23 = MulAdd(z, Splat(-1.98412698298579493134e-04), Splat(8.33333333332248946124e-03));
  const Lanes s45 = MulAdd(z, Splat(-2.50507602534068634195e-08), Splat(2.75573137070700676789e-06));
  const Lanes s2_6 = MulAdd(z2, MulAdd(z2, Splat(1.58969099521155010221e-10), s45), s23);
  const Lanes sine = MulAdd(v, MulAdd(z, s2_6, Splat(-1.66666666666666324348e-01)), y);
  const Lanes z4 = z2 * z2;
  const Lanes c12 = MulAdd(z, Splat(-1.38888888888741095749e-03), Splat(4.16666666666666019037e-02));
  const Lanes c34 = MulAdd(z, Splat(-2.75573143513906633035e-07), Splat(2.48015872894767294178e-05));
  const Lanes c56 = MulAdd(z, Splat(-1.13596475577881948265e-11), Splat(2.08757232129817482790e-09));
  const Lanes c1_6 = MulAdd(z4, c56, MulAdd(z2, c34, c12));
  const Lanes half_z = 0.5 * z;
  const Lanes w = 1.0 - half_z;
  const Lanes cosine = w + MulAdd(z2, c1_6, (1.0 - w) - half_z);
  // Quadrant q: (sin, cos) = (s, c), (c, −s), (−s, −c), (−c, s).
  const Mask odd = (quadrant & 1) != 0;
  const Mask sine_negative = (quadrant & 2) != 0;
  const Mask cosine_negative = ((quadrant + 1) & 2) != 0;
  const Mask sign_bit = Mask{} | INT64_MIN;  // the sign bit alone
  const Mask sin_bits = (odd & std::bit_cast<Mask>(cosine)) | (~odd & std::bit_cast<Mask>(sine));
  const Mask cos_bits = (odd & std::bit_cast<Mask>(sine)) | (~odd & std::bit_cast<Mask>(cosine));
  *s = std::bit_cast<Lanes>(sin_bits ^ (sine_negative & sign_bit));
  *c = std::bit_cast<Lanes>(cos_bits ^ (cosine_negative & sign_bit));
  // The library for lanes beyond the reduction's range.
  const auto inside = Abs(x) < kLanesSinCosLimit;
  if (__builtin_expect(!(inside[0] & inside[1] & inside[2] & inside[3]), 0)) {
    for (int e = 0; e < 4; ++e) {
      if (inside[e]) continue;
      (*s)[e] = std::sin(x[e]);
      (*c)[e] = std::cos(x[e]);
    }
  }
}

}  // namespace dpc

#pragma GCC diagnostic pop
