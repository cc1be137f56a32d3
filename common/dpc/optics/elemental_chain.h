#pragma once
// Chains of 3 or 4 fixed-axis stages on S1, S2, S3 — the paper's devices — as fixed-size code:
// the kinematics of the fused control update (control/fused_gradient_projection.h) and of the
// simulator's fast path.
//
// The mathematics are WaveplateChain's (waveplate_chain.h) for this class of chains, unrolled:
// B_e = M_e ⋯ M_1 in named scalars, each stage's axis carried to the input frame, B_(e−1)ᵀ a_e
// (a row of B_(e−1): Ω′_e = (dθ_e/dφ_e)·B_(e−1)ᵀ a_e), and M = B_m, in one forward pass.
//
// Axes known at compile time (FixedStageAxes; the paper's R1R3R1 and R1R3R1R3 are
// PaperAxes3 and PaperAxes4) make the entries of B that are exactly 0 or 1 known too: B_0 = I and
// a rotation mixes only two rows, so B_1 is the first stage's rotation and B_2 keeps one zero.
// The code never multiplies by them: a fifth less arithmetic in the forward pass and a shorter
// dependency chain (B_2's entries are single products). Any other sequence of elemental axes
// runs the same code with the axes read at run time (RuntimeStageAxes). The operations are
// those of WaveplateChain::Evaluate and ::Output (a product with a known zero or one is exact);
// the results agree to the last bit or two, not always exactly: GCC 12's vectorizer may pair a
// rotation's two rows, (c·u − s·v, s·u + c·v), into one fused multiply-add-subtract even with
// -ffp-contract=off, in one context and not in another. A build gives the same bits on every
// run either way.
//
// Real-time: nothing here allocates; everything is inline and unrolled.

#include <array>
#include <cmath>

#include "dpc/optics/count_dispatch.h"
#include "dpc/optics/lanes.h"
#include "dpc/optics/rotation.h"
#include "dpc/optics/stokes.h"

namespace dpc {

/// Stage axes in the order the light meets them, known at compile time.
template <ElementalAxis... kAxes>
struct FixedStageAxes {
  static constexpr int kStages = sizeof...(kAxes);
  static constexpr bool kFixed = true;
  static constexpr ElementalAxis At(int stage) {
    constexpr ElementalAxis axes[] = {kAxes...};
    return axes[stage];
  }
};

/// Stage axes read at run time (each S1, S2 or S3).
template <int N>
struct RuntimeStageAxes {
  static constexpr int kStages = N;
  static constexpr bool kFixed = false;
  ElementalAxis axis[N];
  ElementalAxis At(int stage) const { return axis[stage]; }
};

/// The paper's devices in light order: M = R1R3R1 and M = R1R3R1R3.
using PaperAxes3 = FixedStageAxes<ElementalAxis::kS1, ElementalAxis::kS3, ElementalAxis::kS1>;
using PaperAxes4 = FixedStageAxes<ElementalAxis::kS3, ElementalAxis::kS1, ElementalAxis::kS3,
                                  ElementalAxis::kS1>;

/// Calls f with the axes of a chain of `stages` (3 or 4) elemental axes (light order): the
/// paper's devices as their compile-time types, any other sequence as RuntimeStageAxes.
template <typename F>
decltype(auto) DispatchStageAxes(const ElementalAxis* axes, int stages, F&& f) {
  const auto is = [&](auto fixed) {
    for (int e = 0; e < fixed.kStages; ++e) {
      if (axes[e] != fixed.At(e)) return false;
    }
    return true;
  };
  if (stages == 3) {
    if (is(PaperAxes3{})) return f(PaperAxes3{});
    return f(RuntimeStageAxes<3>{{axes[0], axes[1], axes[2]}});
  }
  if (is(PaperAxes4{})) return f(PaperAxes4{});
  return f(RuntimeStageAxes<4>{{axes[0], axes[1], axes[2], axes[3]}});
}

/// A command of a chain of N elemental stages: φ, and the sines and cosines of the stage
/// angles θ_e = k_e·φ_e + θ0_e, stage e in lane e (lanes.h). A 3-stage chain's fourth lane is an
/// idle control at φ = 0, θ = 0: the per-control arithmetic runs on all four lanes at once.
template <int N>
struct ElementalPose {
  static_assert(N >= 1 && N <= 4);
  Lanes phi = {0.0, 0.0, 0.0, 0.0};
  Lanes cos = {1.0, 1.0, 1.0, 1.0};
  Lanes sin = {0.0, 0.0, 0.0, 0.0};
  /// Updates by angle addition since the sines and cosines were last evaluated exactly.
  int incremental_steps = 0;
};

/// Real-time. S_out = M S_in at `pose` (paper eq. 2).
template <typename Axes, int N>
[[gnu::always_inline]] inline StokesVector ElementalOutput(const Axes& axes,
                                                           const ElementalPose<N>& pose,
                                                           const StokesVector& s_in) {
  double x = s_in[0], y = s_in[1], z = s_in[2];
  ForEachIndex<N>([&](auto e) { RotateElemental(axes.At(e), pose.cos[e()], pose.sin[e()], x, y, z); });
  return StokesVector(x, y, z);
}

namespace elemental_chain_detail {

// What an entry of B is known to be.
enum class Entry : unsigned char { kZero, kOne, kValue };
using Pattern = std::array<std::array<Entry, 3>, 3>;

// The row of B that is the axis in the input frame, and the rows a rotation about it mixes:
// (i, j) ← (c·i − s·j, s·i + c·j) (R1 mixes rows 1, 2; R2 rows 2, 0; R3 rows 0, 1).
constexpr int AxisRow(ElementalAxis axis) { return static_cast<int>(axis) - 1; }
constexpr int FirstMixedRow(ElementalAxis axis) { return (AxisRow(axis) + 1) % 3; }
constexpr int SecondMixedRow(ElementalAxis axis) { return (AxisRow(axis) + 2) % 3; }

constexpr Pattern kIdentity = {{{Entry::kOne, Entry::kZero, Entry::kZero},
                                {Entry::kZero, Entry::kOne, Entry::kZero},
                                {Entry::kZero, Entry::kZero, Entry::kOne}}};
constexpr Pattern kAllValues = {{{Entry::kValue, Entry::kValue, Entry::kValue},
                                 {Entry::kValue, Entry::kValue, Entry::kValue},
                                 {Entry::kValue, Entry::kValue, Entry::kValue}}};

// The pattern of M_axis·B for B of pattern `p`: a mixed entry is 0 if both it and its partner
// were 0, else a value.
constexpr Pattern Rotated(const Pattern& p, ElementalAxis axis) {
  Pattern out = p;
  const int i = FirstMixedRow(axis), j = SecondMixedRow(axis);
  for (int c = 0; c < 3; ++c) {
    const bool zero = p[i][c] == Entry::kZero && p[j][c] == Entry::kZero;
    out[i][c] = out[j][c] = zero ? Entry::kZero : Entry::kValue;
  }
  return out;
}

// The pattern of B_e (before stage e's rotation) for compile-time axes.
template <typename Axes>
constexpr Pattern PatternBefore(int stage) {
  Pattern p = kIdentity;
  for (int e = 0; e < stage; ++e) p = Rotated(p, Axes::At(e));
  return p;
}

// (u, v) ← (c·u − s·v, s·u + c·v) for entries of patterns kU, kV, skipping known zeros and ones
// (exact: the same bits as the full expressions for finite values).
// T is double, or a vector of doubles (one lane per trajectory: sim/batch_kernel_impl.h).
template <Entry kU, Entry kV, typename T>
[[gnu::always_inline]] inline void Turn(T& u, T& v, T c, T s) {
  if constexpr (kU == Entry::kZero && kV == Entry::kZero) {
    return;
  } else if constexpr (kU == Entry::kZero) {
    if constexpr (kV == Entry::kOne) {
      u = -s;
      v = c;
    } else {
      u = -(s * v);
      v = c * v;
    }
  } else if constexpr (kV == Entry::kZero) {
    if constexpr (kU == Entry::kOne) {
      u = c;
      v = s;
    } else {
      const T t = u;
      u = c * t;
      v = s * t;
    }
  } else {
    // The columns of B are unit vectors: a 1 has zeros beside it, so both are values here.
    static_assert(kU == Entry::kValue && kV == Entry::kValue);
    const T t = u;
    u = c * t - s * v;
    v = s * t + c * v;
  }
}

}  // namespace elemental_chain_detail

/// A stage's axis in the input frame, B_(e−1)ᵀ a_e: row kRow of B_(e−1), with the entries known
/// to be 0 or 1 (pattern kPattern) left out of its products. T: double or a vector of doubles.
template <elemental_chain_detail::Pattern kPattern, int kRow, typename T = double>
class InputFrameAxis {
 public:
  explicit InputFrameAxis(const T (&b)[3][3]) : b_(b) {}

  /// (B_(e−1)ᵀ a_e)·(x, y, z).
  [[gnu::always_inline]] T Dot(T x, T y, T z) const {
    using elemental_chain_detail::Entry;
    const T w[3] = {x, y, z};
    T sum{};
    bool first = true;
    ForEachIndex<3>([&](auto col) {
      constexpr Entry kind = kPattern[kRow][col];
      if constexpr (kind != Entry::kZero) {
        const T term = kind == Entry::kOne ? w[col] : w[col] * b_[kRow][col];
        sum = first ? term : sum + term;
        first = false;
      }
    });
    return sum;
  }

 private:
  const T (&b_)[3][3];
};

/// Real-time. The forward pass at the sines and cosines of the stage angles: for each stage e in
/// light order, on_stage(e, axis) with e a std::integral_constant and axis the stage's
/// InputFrameAxis (before its rotation is applied); then m = M = B_m (m[row][column]).
/// T is double with `Angles` the Lanes of the stages, or a vector of doubles (a trajectory per
/// lane) with `Angles` an array of them, one per stage.
template <typename Axes, typename Angles, typename T, typename OnStage>
[[gnu::always_inline]] inline void ElementalForwardPass(const Axes& axes, const Angles& cos,
                                                        const Angles& sin, T (&m)[3][3],
                                                        OnStage&& on_stage) {
  using namespace elemental_chain_detail;
  constexpr int N = Axes::kStages;
  const T zero{}, one = zero + 1.0;
  m[0][0] = one, m[0][1] = zero, m[0][2] = zero;
  m[1][0] = zero, m[1][1] = one, m[1][2] = zero;
  m[2][0] = zero, m[2][1] = zero, m[2][2] = one;
  // One stage with its axis and the pattern of B before it as constants.
  const auto stage = [&](auto e, auto axis, auto pattern) {
    constexpr ElementalAxis kAxis = decltype(axis)::value;
    constexpr Pattern kPattern = decltype(pattern)::value;
    constexpr int a = AxisRow(kAxis), i = FirstMixedRow(kAxis), j = SecondMixedRow(kAxis);
    on_stage(e, InputFrameAxis<kPattern, a, T>(m));
    const T c = cos[e()], s = sin[e()];
    ForEachIndex<3>([&](auto col) { Turn<kPattern[i][col], kPattern[j][col]>(m[i][col], m[j][col], c, s); });
  };
  ForEachIndex<N>([&](auto e) {
    if constexpr (Axes::kFixed) {
      stage(e, std::integral_constant<ElementalAxis, Axes::At(e)>{},
            std::integral_constant<Pattern, PatternBefore<Axes>(e)>{});
    } else {
      // B_0 = I whatever the axes; after it only values (the zeros are kept as 0.0 entries).
      using BeforeStage = std::integral_constant<Pattern, e == 0 ? kIdentity : kAllValues>;
      switch (axes.At(e)) {
        case ElementalAxis::kS1:
          stage(e, std::integral_constant<ElementalAxis, ElementalAxis::kS1>{}, BeforeStage{});
          break;
        case ElementalAxis::kS2:
          stage(e, std::integral_constant<ElementalAxis, ElementalAxis::kS2>{}, BeforeStage{});
          break;
        default:  // kS3 (the caller passes elemental axes only)
          stage(e, std::integral_constant<ElementalAxis, ElementalAxis::kS3>{}, BeforeStage{});
          break;
      }
    }
  });
}

}  // namespace dpc
