#pragma once
// Chains of 3 or 4 fixed-axis stages on S1, S2, S3 — the paper's devices — as fixed-size code:
// the kinematics of the fused control update (control/fused_gradient_projection.h), of the
// batched simulator's kernel (sim/batch_kernel_impl.h) and the output of the simulator's fast
// path.
//
// The mathematics are WaveplateChain's (waveplate_chain.h) for this class of chains, unrolled.
// The control update needs of the chain only the reduced task (eq. 8): each stage's axis in the
// input frame, Ω′_e = (dθ_e/dφ_e)·B_(e−1)ᵀa_e (B_e = M_e ⋯ M_1), seen through the tangent basis
// (e1, e2) at S_in, and the target brought back to the input frame, MᵀS*, seen through the same
// basis. ElementalTask turns the two basis vectors through the stages instead of forming B
// (e·(Bᵀa) = (Be)·a, one component of the turned vector): two vectors through m − 1 stages
// instead of a matrix through m, fewer operations and a shorter dependency chain from the pose
// to the task. Both give the general path's results to round-off (elemental_chain_test).
//
// Axes known at compile time (FixedStageAxes; the paper's R1R3R1 and R1R3R1R3 are
// PaperAxes3 and PaperAxes4) let each stage's rotation compile to its two rows without a
// switch. Any other sequence of elemental axes runs the same code with the axes read at run
// time (RuntimeStageAxes).
//
// Real-time: nothing here allocates; everything is inline and unrolled.

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

/// Real-time. The kinematics and task of the fused control update
/// (control/fused_gradient_projection.h) at the sines and cosines of the stage angles, with the
/// tangent basis (e1, e2) at S_in carried through the chain instead of the chain's matrix:
///
///   T's row of stage e  (e2·Ω′_e, −e1·Ω′_e) with Ω′_e = k_e·B_(e−1)ᵀa_e (k_e = dθ_e/dφ_e) is
///                       (k_e·(B_(e−1)e2)[a_e], −k_e·(B_(e−1)e1)[a_e]): a component each of the
///                       basis vectors turned by the stages before e;
///   the task error      e = Eᵀ(MᵀS* − S_in) = ((B_(m−1)e1)·w − e1·S_in, (B_(m−1)e2)·w − e2·S_in)
///                       with w = M_mᵀS* (the target turned back through the last stage,
///                       off the chain: it needs only that stage's angle).
///
/// Two vectors turn through m − 1 stages where the matrix takes three columns through m, and
/// neither M nor B's other rows are formed. on_row(stage, row0, row1) is called for each stage
/// in light order (stage a std::integral_constant); then error0, error1 are set. (sx, sy, sz) is
/// the output-frame vector the error looks at: S* in the model loop, with in0 = e1·S_in and
/// in1 = e2·S_in; S* − S_out in the measured loop, with in0 = in1 = 0. T: double with `Angles`
/// and `Scales` the Lanes of the stages, or a vector of doubles (a trajectory per lane) with
/// arrays of them, one per stage; both give the same bits lane by lane. e1, e2: anything whose
/// [0], [1], [2] are the basis vector's components as T.
template <typename Axes, typename Angles, typename Scales, typename Basis, typename T,
          typename OnRow>
[[gnu::always_inline]] inline void ElementalTask(const Axes& axes, const Angles& cos,
                                                 const Angles& sin, const Scales& k,
                                                 const Basis& e1, const Basis& e2, T sx, T sy,
                                                 T sz, T in0, T in1, OnRow&& on_row, T* error0,
                                                 T* error1) {
  constexpr int N = Axes::kStages;
  // w: (sx, sy, sz) turned back through the last stage (M_mᵀ), from the pose alone.
  T wx = sx, wy = sy, wz = sz;
  RotateElemental<T>(axes.At(N - 1), cos[N - 1], -sin[N - 1], wx, wy, wz);
  T u1[3] = {e1[0], e1[1], e1[2]}, u2[3] = {e2[0], e2[1], e2[2]};
  // Component `axis` of u (a switch on a run-time axis: u stays in registers).
  const auto component = [](const T (&u)[3], ElementalAxis axis) -> T {
    switch (axis) {
      case ElementalAxis::kS1: return u[0];
      case ElementalAxis::kS2: return u[1];
      default: return u[2];  // kS3 (elemental axes only)
    }
  };
  ForEachIndex<N>([&](auto stage) {
    constexpr int e = stage();
    const ElementalAxis axis = axes.At(e);
    const T ke = k[e];
    on_row(stage, ke * component(u2, axis), -ke * component(u1, axis));
    if constexpr (e + 1 < N) {
      const T c = cos[e], s = sin[e];
      RotateElemental(axis, c, s, u1[0], u1[1], u1[2]);
      RotateElemental(axis, c, s, u2[0], u2[1], u2[2]);
    }
  });
  *error0 = (u1[0] * wx + u1[1] * wy) + (u1[2] * wz - in0);
  *error1 = (u2[0] * wx + u2[1] * wy) + (u2[2] * wz - in1);
}

/// Real-time. G = T·Tᵀ and T·φ of the fused control update, accumulated as ElementalTask's rows
/// arrive (the last stage's row is the latest: each sum takes it in one multiply-add). T: double
/// or a vector of doubles; mul_add(a, b, c) = a·b + c as in SmallAngleTurn.
template <typename T>
struct TaskGram {
  T g11{}, g22{}, g12{}, z0{}, z1{};

  template <typename MulAddFn>
  [[gnu::always_inline]] void Add(bool first, T row0, T row1, T phi, MulAddFn mul_add) {
    if (first) {
      g11 = row0 * row0, g22 = row1 * row1, g12 = row0 * row1;
      z0 = row0 * phi, z1 = row1 * phi;
    } else {
      g11 = mul_add(row0, row0, g11), g22 = mul_add(row1, row1, g22);
      g12 = mul_add(row0, row1, g12);
      z0 = mul_add(row0, phi, z0), z1 = mul_add(row1, phi, z1);
    }
  }
};

}  // namespace dpc
