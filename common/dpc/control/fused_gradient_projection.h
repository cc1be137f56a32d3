#pragma once
// The fused control update: one controller step (paper eqs. 3, 5, 6 with gradient projection,
// eqs. 9–10, or the pseudo-inverse) for the paper's class of configurations, as one fixed-size,
// unrolled pass. PolarizationController runs it for these configurations (the DDS controller's
// step), the simulator's fast path inlines it into its loop.
//
// The class (PlanFusedUpdate): 3 or 4 fixed-axis stages on S1/S2/S3 with linear maps
// θ = k·φ + θ0 and no ranges, a point target, gp / gpt / pinv without the options beyond the
// paper, either loop mode. The paper's R1R3R1 and R1R3R1R3 have their axes fixed at compile
// time (optics/elemental_chain.h), other axis sequences read them at run time.
//
// Per update, the general path's equations (control_problem.h, task_pseudo_inverse.h,
// gradient_projection_law.h, control_integrator.h, WaveplateChain::ComputePoseFrom):
//   kinematics  each stage's axis in the input frame, Ω′_e = k_e·B_(e−1)ᵀa_e (B_e = M_e⋯M_1),
//               seen through the tangent basis (e1, e2) of the measured S_in
//   task        T = [e2ᵀΩ′; −e1ᵀΩ′], e = Eᵀ(MᵀS* − S_in) (model loop) or EᵀMᵀ(S* − S_out
//               measured); both by ElementalTask (optics/elemental_chain.h), which turns e1 and
//               e2 through the stages instead of forming M
//   law         Δφ = Tᵀ·adj(G)·(μe + μ_N·Tφ)/det G − μ_N·φ, G = TTᵀ, while det G > 1e-6·tr²G;
//               near a singularity the general one-sided Jacobi TaskPseudoInverse
//   integrator  φ ← φ + Δφ unless Δφ is not finite
//   pose        the new command's sines and cosines by angle addition, δ_e = k_e·Δφ_e (series
//               for |δ| < 2^-7); exactly from φ every kMaxIncrementalSteps updates and after a
//               larger step
//
// What makes it fast: the update is a dependency chain from one command to the next (pose →
// turned basis → T → G → det G → 1/det G → Δφ → pose), and it is also heavy in multiplications,
// so both its length and its operation count set the time. Ordered for it: the basis, the target
// turned back through the last stage (w = M_mᵀS*) and φ's projections wait off the chain; the
// basis turns through m − 1 stages (two vectors, not M's three columns through m); G
// accumulates as each stage's row arrives (the last stage's is the latest); Tᵀ·adj(G) is formed
// from T and G while the task error is still on its way, so the error reaches v =
// Tᵀ·adj(G)·(μe + μ_N·Tφ) in one product and one sum, and 1/det G is followed by one fused
// multiply-add to reach δ; the new pose's series runs in x⁴ beside the pairs of terms, with δ
// multiplied into the old sine and cosine meanwhile (SmallAngleTurn, rotation.h). Everything
// stays in registers (no arrays indexed at run time, no address of the pose taken); the rare
// cases (near-singular task, a non-finite Δφ, an exact re-evaluation) leave the straight path
// through one predicted branch each. Only round-off separates it from the general path (tests
// compare the two).

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include "dpc/control/controller_config.h"
#include "dpc/control/singular_values.h"
#include "dpc/control/target.h"
#include "dpc/control/task_pseudo_inverse.h"
#include "dpc/optics/elemental_chain.h"
#include "dpc/optics/waveplate_chain.h"

namespace dpc {

/// What the fused update needs to know, fixed when it is built.
struct FusedUpdatePlan {
  int stages = 0;
  ElementalAxis axis[4] = {};  ///< light order
  double rad_per_unit[4] = {}, offset_rad[4] = {};
  double step = 0.0;
  double nullspace_step = 0.0;  ///< μ_N; 0 for pinv
  std::optional<double> threshold;  ///< gpt
  double singular_value_tolerance = 1e-12;
  LoopMode loop = LoopMode::kModel;
  StokesVector target_point = StokesVector::UnitX();
};

/// The plan if the chain, target and controller are in the fused update's class (see the file
/// comment), else nullopt. A user's law factory is the caller's to rule out.
std::optional<FusedUpdatePlan> PlanFusedUpdate(const WaveplateChain& chain, const Target& target,
                                               const ControllerConfig& config);

/// What one fused update did.
struct FusedUpdateResult {
  bool applied = false;           ///< Δφ was finite: the command and its pose moved
  bool nullspace_active = false;  ///< the null-space term ran
  int rank = 2;                   ///< of T
  SingularValues singular_values;
};

template <typename Axes>
class FusedGradientProjection {
 public:
  static constexpr int kStages = Axes::kStages;
  using Pose = ElementalPose<kStages>;

  FusedGradientProjection(const FusedUpdatePlan& plan, const Axes& axes)
      : axes_(axes),
        step_(plan.step),
        nullspace_step_(plan.nullspace_step),
        has_threshold_(plan.threshold.has_value()),
        threshold_(plan.threshold.value_or(0.0)),
        measured_(plan.loop == LoopMode::kMeasured),
        target_(plan.target_point),
        fallback_(plan.singular_value_tolerance),
        fallback_task_(2, kStages),
        fallback_error_(2),
        fallback_phi_(kStages),
        fallback_delta_(kStages) {
    for (int e = 0; e < kStages; ++e) {
      rad_per_unit_[e] = plan.rad_per_unit[e];
      offset_rad_[e] = plan.offset_rad[e];
    }
  }

  /// Real-time. Sets `pose` to the command pose->phi exactly: the four stages' sines and cosines
  /// at once (SinCos of lanes.h, within ~2 ulp of the library's).
  [[gnu::always_inline]] void ExactPose(Pose* pose) const {
    SinCos(rad_per_unit_ * pose->phi + offset_rad_, &pose->sin, &pose->cos);
    pose->incremental_steps = 0;
  }

  /// Real-time. One update from the measured S_in (and S_out, used in the measured loop) at the
  /// command `pose`, which becomes the new command's pose (unchanged when Δφ is not finite).
  /// Writes Δφ into delta_phi[0 … kStages) (zero when not applied).
  [[gnu::always_inline]] FusedUpdateResult Update(const StokesVector& s_in,
                                                  const StokesVector& s_out_measured, Pose* pose,
                                                  double* delta_phi) {
    FusedUpdateResult result;
    Vector3 e1, e2;
    TangentBasis(s_in, &e1, &e2);
    // What the task error looks at in the output frame: S*, or S* − S_out in the measured loop.
    double sx, sy, sz;
    if (measured_) {
      sx = target_[0] - s_out_measured[0], sy = target_[1] - s_out_measured[1],
      sz = target_[2] - s_out_measured[2];
    } else {
      sx = target_[0], sy = target_[1], sz = target_[2];
    }
    // e1·S_in, e2·S_in of the model loop's e = Eᵀ(MᵀS* − S_in): 0 up to rounding for a unit
    // S_in, kept so that a measured S_in off the sphere gives the general path's error.
    const double in0 = measured_ ? 0.0 : e1[0] * s_in[0] + e1[1] * s_in[1] + e1[2] * s_in[2];
    const double in1 = measured_ ? 0.0 : e2[0] * s_in[0] + e2[1] * s_in[1] + e2[2] * s_in[2];
    // Kinematics, task rows and task error (ElementalTask); G and Tφ accumulate as the rows
    // arrive.
    const Lanes phi = pose->phi;
    double rows0[4] = {}, rows1[4] = {};
    TaskGram<double> gram;
    double error0, error1;
    ElementalTask(
        axes_, pose->cos, pose->sin, rad_per_unit_, e1, e2, sx, sy, sz, in0, in1,
        [&](auto stage, double row0, double row1) {
          constexpr int e = stage();
          rows0[e] = row0;
          rows1[e] = row1;
          gram.Add(e == 0, row0, row1, phi[e],
                   [](double a, double b, double c) { return MulAdd(a, b, c); });
        },
        &error0, &error1);
    const double g11 = gram.g11, g22 = gram.g22, g12 = gram.g12, z0 = gram.z0, z1 = gram.z1;
    const Lanes t0 = {rows0[0], rows0[1], rows0[2], rows0[3]};
    const Lanes t1 = {rows1[0], rows1[1], rows1[2], rows1[3]};
    // Law: the null-space term (gpt: while some |φ_i| > threshold).
    double mu_null = nullspace_step_;
    if (has_threshold_ && !(MaxLane(Abs(phi)) > threshold_)) mu_null = 0.0;
    result.nullspace_active = mu_null > 0.0;
    const double trace = g11 + g22, det = g11 * g22 - g12 * g12;
    Lanes delta, dtheta;
    if (__builtin_expect(det > kWellConditioned * trace * trace, 1)) {
      const double inverse_det = 1.0 / det;
      // Tᵀ·adj(G) from the rows and G while the task error is still on its way; then
      // v = Tᵀ·adj(G)·(μe + μ_N·Tφ) is one product and one sum after it, and Δφ one multiply-add
      // after the division.
      const Lanes p0 = t0 * g22 - t1 * g12, p1 = t1 * g11 - t0 * g12;
      const double r0 = step_ * error0 + mu_null * z0, r1 = step_ * error1 + mu_null * z1;
      const Lanes v = p0 * r0 + p1 * r1;
      const Lanes inverse = Splat(inverse_det);
      delta = MulAdd(v, inverse, -mu_null * phi);
      dtheta = MulAdd(rad_per_unit_ * v, inverse, -(mu_null * rad_per_unit_) * phi);
      result.singular_values = SingularValues::FromGram(g11, g22, g12, det);
    } else {
      result.rank = SolveNearSingularity(t0, t1, error0, error1, phi, mu_null, &delta,
                                         &result.singular_values);
      dtheta = rad_per_unit_ * delta;
    }
    // The new command and its pose, kept only if Δφ is finite and the steps are small.
    Lanes cos_next, sin_next;
    SmallAngleTurn(
        pose->cos, pose->sin, dtheta, [](Lanes a, Lanes b, Lanes c) { return MulAdd(a, b, c); },
        &cos_next, &sin_next);
    result.applied = SumLanes(0.0 * delta) == 0.0;  // 0·x is NaN for NaN and ±Inf
    const bool small = MaxLane(Abs(dtheta)) < kSmallAngleLimit;
    const bool incremental =
        result.applied & small & (pose->incremental_steps < WaveplateChain::kMaxIncrementalSteps);
    if (__builtin_expect(incremental, 1)) {
      pose->phi = phi + delta;
      pose->cos = cos_next;
      pose->sin = sin_next;
      ++pose->incremental_steps;
    } else if (result.applied) {
      pose->phi = phi + delta;
      ExactPose(pose);
    } else {
      delta = Lanes{};
    }
    for (int e = 0; e < kStages; ++e) delta_phi[e] = delta[e];
    return result;
  }

  /// det G above this fraction of (tr G)² takes the normal equations (as TaskPseudoInverse).
  static constexpr double kWellConditioned = 1e-6;

  /// Δφ by the general one-sided Jacobi pseudo-inverse at the task rows t0, t1 (what Update does
  /// near a singularity; the batched simulator calls it for one lane); returns the rank.
  [[gnu::noinline]] int SolveNearSingularity(Lanes t0, Lanes t1, double error0, double error1,
                                             Lanes phi, double mu_null, Lanes* delta,
                                             SingularValues* singular_values) {
    for (int e = 0; e < kStages; ++e) {
      fallback_task_(0, e) = t0[e];
      fallback_task_(1, e) = t1[e];
      fallback_phi_[e] = phi[e];
    }
    fallback_error_ << error0, error1;
    fallback_.Compute(fallback_task_);
    fallback_.GradientProjectionStep(fallback_error_, fallback_phi_, step_, mu_null,
                                     &fallback_delta_);
    *delta = Lanes{};
    for (int e = 0; e < kStages; ++e) (*delta)[e] = fallback_delta_[e];
    *singular_values = fallback_.singular_values();
    return fallback_.rank();
  }

 private:

  Axes axes_;
  // Per lane; an idle lane (3 stages) has k = 0, θ0 = 0.
  Lanes rad_per_unit_ = {0.0, 0.0, 0.0, 0.0};
  Lanes offset_rad_ = {0.0, 0.0, 0.0, 0.0};
  double step_, nullspace_step_;
  bool has_threshold_;
  double threshold_;
  bool measured_;
  StokesVector target_;
  TaskPseudoInverse fallback_;
  TaskJacobian fallback_task_;
  TaskVector fallback_error_;
  ControlVector fallback_phi_, fallback_delta_;
};

/// A fused update with its command's pose behind one virtual call, for a caller that holds
/// the update of whichever chain it was given (PolarizationController).
class FusedControlStep {
 public:
  /// The step for `plan` (the paper's axes at compile time, others at run time).
  static std::unique_ptr<FusedControlStep> Make(const FusedUpdatePlan& plan);
  virtual ~FusedControlStep() = default;

  /// Real-time. The command becomes `phi` (its pose exactly).
  virtual void SetCommand(const ControlVector& phi) = 0;
  /// Real-time. The command becomes the one of `pose`, a pose of the plan's chain (whose
  /// elements are its stages).
  virtual void SetPose(const ChainPose& pose) = 0;
  /// Real-time. FusedGradientProjection::Update at the current command, which becomes the new
  /// one; Δφ into delta_phi (resized to the stage count).
  virtual FusedUpdateResult Update(const StokesVector& s_in, const StokesVector& s_out_measured,
                                   ControlVector* delta_phi) = 0;
};

}  // namespace dpc
