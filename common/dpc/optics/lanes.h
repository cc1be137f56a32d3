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

/// SmallAngleSinCosFused (rotation.h) lane by lane.
[[gnu::always_inline]] inline void SmallAngleSinCosFused(Lanes x, Lanes* s, Lanes* c) {
  const Lanes x2 = x * x;
  *s = x * MulAdd(x2, MulAdd(x2, MulAdd(x2, Splat(-1.0 / 5040), Splat(1.0 / 120)), Splat(-1.0 / 6)),
                  Splat(1.0));
  *c = MulAdd(x2, MulAdd(x2, MulAdd(x2, Splat(-1.0 / 720), Splat(1.0 / 24)), Splat(-0.5)),
              Splat(1.0));
}

}  // namespace dpc

#pragma GCC diagnostic pop
