#pragma once
// The batched kernel (batch_kernel.h) for W lanes: included only by batch_kernel_avx2.cc (W = 4)
// and batch_kernel_avx512.cc (W = 8), each compiled for its instruction set. Everything here has
// internal linkage, so no unit built for AVX-512 defines a function another unit might call on
// a processor without it.
//
// Each lane repeats, operation for operation, what the scalar fast path does for its trajectory
// (closed_loop_simulator_fast_path.cc with FusedGradientProjection::Update): the same products,
// sums and fused multiply-adds in the same order, so a lane's trajectory is the scalar one's.
// Where a lane leaves the straight path (a near-singular task, an exact pose, a noisy output
// polarimeter), the simulator's scalar code does that lane's step through a callback.

#include <immintrin.h>

#include <bit>
#include <cstdint>
#include <cstring>

#include "dpc/optics/elemental_chain.h"
#include "dpc/sim/batch_kernel.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace dpc {
namespace {

template <int W>
struct BatchTypes;
template <>
struct BatchTypes<4> {
  using V = double __attribute__((vector_size(32)));
  using M = int64_t __attribute__((vector_size(32)));
};
template <>
struct BatchTypes<8> {
  using V = double __attribute__((vector_size(64)));
  using M = int64_t __attribute__((vector_size(64)));
};

template <int W>
struct BatchMath {
  using V = typename BatchTypes<W>::V;
  using M = typename BatchTypes<W>::M;

  [[gnu::always_inline]] static V Load(const double* p) {
    V v;
    std::memcpy(&v, p, sizeof(V));
    return v;
  }
  [[gnu::always_inline]] static void Store(double* p, V v) { std::memcpy(p, &v, sizeof(V)); }
  [[gnu::always_inline]] static V Splat(double x) { return V{} + x; }
  [[gnu::always_inline]] static M Mask(const bool* lanes) {
    M m{};
    for (int l = 0; l < W; ++l) m[l] = lanes[l] ? -1 : 0;
    return m;
  }
  [[gnu::always_inline]] static V Select(M mask, V a, V b) {
    return mask != 0 ? a : b;  // a blend (AVX2) or a masked move (AVX-512)
  }
  /// Bit l set for each lane l whose mask is set.
  [[gnu::always_inline]] static unsigned Bits(M mask) {
    if constexpr (W == 4) {
      return static_cast<unsigned>(_mm256_movemask_pd(std::bit_cast<__m256d>(mask)));
    } else {
#ifdef __AVX512DQ__
      return static_cast<unsigned>(_mm512_movepi64_mask(std::bit_cast<__m512i>(mask)));
#else
      unsigned bits = 0;
      for (int l = 0; l < W; ++l) bits |= (mask[l] != 0 ? 1u : 0u) << l;
      return bits;
#endif
    }
  }
  /// The low byte of each lane of `m`, stored at p[0 … W).
  [[gnu::always_inline]] static void StoreBytes(uint8_t* p, M m) {
#ifdef __AVX512F__
    if constexpr (W == 8) {
      _mm_storel_epi64(reinterpret_cast<__m128i*>(p), _mm512_cvtepi64_epi8(std::bit_cast<__m512i>(m)));
      return;
    }
#endif
    for (int l = 0; l < W; ++l) p[l] = static_cast<uint8_t>(m[l]);
  }
  /// a·b + c: one rounding when kFused (as MulAdd of rotation.h / lanes.h in the scalar build).
  template <bool kFused>
  [[gnu::always_inline]] static V MulAdd(V a, V b, V c) {
    if constexpr (!kFused) {
      return a * b + c;
    } else if constexpr (W == 4) {
      return std::bit_cast<V>(_mm256_fmadd_pd(std::bit_cast<__m256d>(a), std::bit_cast<__m256d>(b),
                                              std::bit_cast<__m256d>(c)));
    } else {
#ifdef __AVX512F__
      return std::bit_cast<V>(_mm512_fmadd_pd(std::bit_cast<__m512d>(a), std::bit_cast<__m512d>(b),
                                              std::bit_cast<__m512d>(c)));
#else
      static_assert(W == 4, "the 8-lane kernel is built for AVX-512");
#endif
    }
  }
  [[gnu::always_inline]] static V Abs(V x) {
    return std::bit_cast<V>(std::bit_cast<M>(x) & INT64_MAX);
  }
  /// copysign(1, x) lane by lane.
  [[gnu::always_inline]] static V SignOne(V x) {
    const M sign = std::bit_cast<M>(x) & INT64_MIN;
    return std::bit_cast<V>(sign | std::bit_cast<M>(Splat(1.0)));
  }
  /// RotateElemental (rotation.h) lane by lane.
  [[gnu::always_inline]] static void Rotate(ElementalAxis axis, V c, V s, V& x, V& y, V& z) {
    RotateElemental<V>(axis, c, s, x, y, z);
  }
};

/// One block for W lanes of the chain `axes`; see batch_kernel.h.
template <int W, bool kFused, typename Axes>
void RunBatchBlockFor(BatchLanes& lanes, const BatchBlock& block, const Axes& axes) {
  using Math = BatchMath<W>;
  using V = typename Math::V;
  using M = typename Math::M;
  constexpr int N = Axes::kStages;
  constexpr int kLineStride = 3 * 4 * kMaxBatchLanes;  // doubles per slot
  const auto fma = [](V a, V b, V c) { return Math::template MulAdd<kFused>(a, b, c); };

  // The lanes' plans.
  V k[N];
  for (int e = 0; e < N; ++e) k[e] = Math::Load(lanes.rad_per_unit[e]);
  const V step = Math::Load(lanes.step), nullspace_step = Math::Load(lanes.nullspace_step);
  const V threshold = Math::Load(lanes.threshold);
  const V target_x = Math::Load(lanes.target[0]), target_y = Math::Load(lanes.target[1]),
          target_z = Math::Load(lanes.target[2]);
  const M has_threshold = Math::Mask(lanes.has_threshold);
  const M measured_loop = Math::Mask(lanes.measured_loop);
  const unsigned noisy = Math::Bits(Math::Mask(lanes.noisy_output));

  // The command's pose, in registers through the block.
  V phi[4] = {}, cosine[4], sine[4] = {};
  for (int e = 0; e < 4; ++e) cosine[e] = Math::Splat(1.0);
  for (int e = 0; e < N; ++e) {
    phi[e] = Math::Load(lanes.phi[e]);
    cosine[e] = Math::Load(lanes.cos[e]);
    sine[e] = Math::Load(lanes.sin[e]);
  }
  M incremental_steps{};
  for (int l = 0; l < W; ++l) incremental_steps[l] = lanes.incremental_steps[l];
  // The input (vector_input): the SOP and the scrambler's parameters.
  V sop_x = Math::Load(lanes.sop[0]), sop_y = Math::Load(lanes.sop[1]),
    sop_z = Math::Load(lanes.sop[2]);
  const V step_cos = Math::Load(lanes.input_step_cos), step_sin = Math::Load(lanes.input_step_sin);
  const V kick_sigma = Math::Load(lanes.input_kick_sigma);
  const M kick = kick_sigma > 0.0;
  const unsigned kick_bits = Math::Bits(kick);
  const unsigned noisy_input = Math::Bits(Math::Mask(lanes.noisy_input));
  const int64_t line_size = lanes.delay_samples;
  int64_t slot = lanes.slot;

  for (int i = 0; i < block.count; ++i) {
    const int64_t sample = block.first_sample + i;
    const int at = i * kMaxBatchLanes;
    double* applied = lanes.line + slot * kLineStride;
    V x, y, z;
    if (lanes.vector_input) {
      // InputSopGenerator::Next with PaperScrambler::Advance: the step, the kick, |S| = 1.
      if (sample > 0) {
        Math::Rotate(lanes.input_rotation_axis, step_cos, step_sin, sop_x, sop_y, sop_z);
        if (kick_bits != 0) {
          // SinCos: the series below kSmallAngleLimit, the library beyond (the scalar build's).
          const V a = kick_sigma * Math::Load(block.normals + at);
          V s, c;
          SmallAngleSinCos(a, &s, &c);
          const M series = (a > -kSmallAngleLimit) & (a < kSmallAngleLimit);
          for (unsigned bits = kick_bits & ~Math::Bits(series); bits != 0; bits &= bits - 1) {
            const int l = __builtin_ctz(bits);
            double s_l, c_l;
            lanes.sin_cos(a[l], &s_l, &c_l);
            s[l] = s_l, c[l] = c_l;
          }
          V kx = sop_x, ky = sop_y, kz = sop_z;
          Math::Rotate(lanes.input_kick_axis, c, s, kx, ky, kz);
          sop_x = Math::Select(kick, kx, sop_x);
          sop_y = Math::Select(kick, ky, sop_y);
          sop_z = Math::Select(kick, kz, sop_z);
        }
        const V f = 0.5 * (3.0 - ((sop_x * sop_x + sop_y * sop_y) + sop_z * sop_z));
        sop_x = sop_x * f, sop_y = sop_y * f, sop_z = sop_z * f;
      }
      x = sop_x, y = sop_y, z = sop_z;
    } else {
      x = Math::Load(block.s_in[0] + at), y = Math::Load(block.s_in[1] + at),
      z = Math::Load(block.s_in[2] + at);
    }
    // The plant: S_out = M(φ applied) S_in, with the command of D samples ago.
    ForEachIndex<N>([&](auto e) {
      const V c = Math::Load(applied + (4 + e()) * kMaxBatchLanes);
      const V s = Math::Load(applied + (8 + e()) * kMaxBatchLanes);
      Math::Rotate(axes.At(e()), c, s, x, y, z);
      Math::Store(block.phi_applied[e()] + at, Math::Load(applied + e() * kMaxBatchLanes));
    });
    Math::Store(block.s_out[0] + at, x);
    Math::Store(block.s_out[1] + at, y);
    Math::Store(block.s_out[2] + at, z);
    if (sample < lanes.activation_sample) {
      std::memset(block.flags + at, 0, kMaxBatchLanes);
      slot = slot + 1 == line_size ? 0 : slot + 1;
      continue;
    }
    // The readings: a polarimeter with noise reads the lanes in `bits` through `measure`.
    const auto read = [&](unsigned bits, auto measure, V& rx, V& ry, V& rz) {
      for (; bits != 0; bits &= bits - 1) {
        const int l = __builtin_ctz(bits);
        const double truth[3] = {rx[l], ry[l], rz[l]};
        double measured[3];
        measure(lanes.context, l, truth, measured);
        rx[l] = measured[0], ry[l] = measured[1], rz[l] = measured[2];
      }
    };
    V in_x, in_y, in_z;
    if (lanes.vector_input) {
      in_x = sop_x, in_y = sop_y, in_z = sop_z;
      read(noisy_input, lanes.measure_input, in_x, in_y, in_z);
    } else {
      in_x = Math::Load(block.measured_in[0] + at), in_y = Math::Load(block.measured_in[1] + at),
      in_z = Math::Load(block.measured_in[2] + at);
    }
    V out_x = x, out_y = y, out_z = z;
    read(noisy, lanes.measure_output, out_x, out_y, out_z);

    // FusedGradientProjection::Update, lane by lane. The tangent basis at the measured S_in.
    V e1[3], e2[3];
    {
      const V sign = Math::SignOne(in_z);
      const V a = -1.0 / (sign + in_z);
      const V b = in_x * in_y * a;
      e1[0] = 1.0 + sign * in_x * in_x * a, e1[1] = sign * b, e1[2] = -sign * in_x;
      e2[0] = b, e2[1] = sign + in_y * in_y * a, e2[2] = -in_y;
    }
    // What the task error looks at (S*, or S* − S_out in the measured loop), and the model
    // loop's E·S_in.
    const V sx = Math::Select(measured_loop, target_x - out_x, target_x);
    const V sy = Math::Select(measured_loop, target_y - out_y, target_y);
    const V sz = Math::Select(measured_loop, target_z - out_z, target_z);
    const V in0 = Math::Select(measured_loop, Math::Splat(0.0),
                               e1[0] * in_x + e1[1] * in_y + e1[2] * in_z);
    const V in1 = Math::Select(measured_loop, Math::Splat(0.0),
                               e2[0] * in_x + e2[1] * in_y + e2[2] * in_z);
    V t0[4] = {}, t1[4] = {};
    TaskGram<V> gram;
    V error0, error1;
    ElementalTask(
        axes, cosine, sine, k, e1, e2, sx, sy, sz, in0, in1,
        [&](auto stage, V row0, V row1) {
          constexpr int e = stage();
          t0[e] = row0;
          t1[e] = row1;
          gram.Add(e == 0, row0, row1, phi[e], fma);
        },
        &error0, &error1);
    const V g11 = gram.g11, g22 = gram.g22, g12 = gram.g12, z0 = gram.z0, z1 = gram.z1;
    // The null-space term (gpt: while some |φ_i| > threshold): MaxLane(Abs(φ)).
    V largest;
    {
      const V a0 = Math::Abs(phi[0]), a1 = Math::Abs(phi[1]), a2 = Math::Abs(phi[2]),
              a3 = Math::Abs(phi[3]);
      const V a = Math::Select(a0 > a1, a0, a1), b = Math::Select(a2 > a3, a2, a3);
      largest = Math::Select(a > b, a, b);
    }
    const V mu_null =
        Math::Select(has_threshold & ~(largest > threshold), Math::Splat(0.0), nullspace_step);
    const V trace = g11 + g22, det = g11 * g22 - g12 * g12;
    const M well = det > lanes.well_conditioned * trace * trace;
    V delta[4] = {}, dtheta[4] = {};
    {
      const V inverse = 1.0 / det;
      const V r0 = step * error0 + mu_null * z0, r1 = step * error1 + mu_null * z1;
      for (int e = 0; e < N; ++e) {
        const V p0 = t0[e] * g22 - t1[e] * g12, p1 = t1[e] * g11 - t0[e] * g12;
        const V v = p0 * r0 + p1 * r1;
        delta[e] = fma(v, inverse, -mu_null * phi[e]);
        dtheta[e] = fma(k[e] * v, inverse, -(mu_null * k[e]) * phi[e]);
      }
    }
    const unsigned well_bits = Math::Bits(well);
    const unsigned all_lanes = (1u << W) - 1;
    for (unsigned bits = ~well_bits & all_lanes; bits != 0; bits &= bits - 1) {
      const int l = __builtin_ctz(bits);
      double row0[4] = {}, row1[4] = {}, phi_l[4] = {}, delta_l[4] = {};
      for (int e = 0; e < N; ++e) row0[e] = t0[e][l], row1[e] = t1[e][l], phi_l[e] = phi[e][l];
      lanes.near_singular(lanes.context, l, i, row0, row1, error0[l], error1[l], phi_l, mu_null[l],
                          delta_l);
      for (int e = 0; e < N; ++e) {
        delta[e][l] = delta_l[e];
        dtheta[e][l] = k[e][l] * delta_l[e];
      }
    }
    // The new command and its pose, kept only if Δφ is finite and the steps are small.
    M finite = ~M{}, small = ~M{};
    V cos_next[4], sin_next[4];
    for (int e = 0; e < N; ++e) {
      SmallAngleTurn(cosine[e], sine[e], dtheta[e], fma, &cos_next[e], &sin_next[e]);
      finite &= 0.0 * delta[e] == 0.0;  // 0·x is NaN for NaN and ±Inf
      small &= Math::Abs(dtheta[e]) < kSmallAngleLimit;
    }
    const M incremental = finite & small & (incremental_steps < lanes.max_incremental_steps);
    for (int e = 0; e < N; ++e) {
      phi[e] = Math::Select(finite, phi[e] + delta[e], phi[e]);
      cosine[e] = Math::Select(incremental, cos_next[e], cosine[e]);
      sine[e] = Math::Select(incremental, sin_next[e], sine[e]);
    }
    incremental_steps -= incremental;  // a set mask is −1
    const unsigned finite_bits = Math::Bits(finite);
    for (unsigned bits = finite_bits & ~Math::Bits(incremental); bits != 0; bits &= bits - 1) {
      const int l = __builtin_ctz(bits);
      double phi_l[4] = {}, cos_l[4], sin_l[4];
      for (int e = 0; e < N; ++e) phi_l[e] = phi[e][l];
      lanes.exact_pose(lanes.context, l, phi_l, cos_l, sin_l);
      for (int e = 0; e < N; ++e) cosine[e][l] = cos_l[e], sine[e][l] = sin_l[e];
      incremental_steps[l] = 0;
    }
    // The outcome, and the command into the delay line.
    // One vector of the lanes' flags, narrowed to a byte per lane.
    const M flags = int64_t{kBatchUpdated} | (finite & int64_t{kBatchApplied}) |
                    ((mu_null > 0.0) & int64_t{kBatchNullspaceActive}) |
                    (~well & int64_t{kBatchNearSingular});
    Math::StoreBytes(block.flags + at, flags);
    Math::Store(block.gram[0] + at, g11);
    Math::Store(block.gram[1] + at, g22);
    Math::Store(block.gram[2] + at, g12);
    Math::Store(block.gram[3] + at, det);
    for (int e = 0; e < N; ++e) {
      Math::Store(applied + e * kMaxBatchLanes, phi[e]);
      Math::Store(applied + (4 + e) * kMaxBatchLanes, cosine[e]);
      Math::Store(applied + (8 + e) * kMaxBatchLanes, sine[e]);
    }
    slot = slot + 1 == line_size ? 0 : slot + 1;
  }

  for (int e = 0; e < N; ++e) {
    Math::Store(lanes.phi[e], phi[e]);
    Math::Store(lanes.cos[e], cosine[e]);
    Math::Store(lanes.sin[e], sine[e]);
  }
  for (int l = 0; l < W; ++l) lanes.incremental_steps[l] = static_cast<int>(incremental_steps[l]);
  lanes.slot = slot;
  Math::Store(lanes.sop[0], sop_x);
  Math::Store(lanes.sop[1], sop_y);
  Math::Store(lanes.sop[2], sop_z);
}

/// RunBatchBlockFor for the lanes' chain and arithmetic.
template <int W>
void RunBatchBlockWith(BatchLanes& lanes, const BatchBlock& block) {
  DispatchStageAxes(lanes.axis, lanes.stages, [&](const auto& axes) {
    if (lanes.fused_multiply_add) {
      RunBatchBlockFor<W, true>(lanes, block, axes);
    } else {
      RunBatchBlockFor<W, false>(lanes, block, axes);
    }
  });
}

}  // namespace
}  // namespace dpc

#pragma GCC diagnostic pop
