#pragma once
// What a control law sees at one sample, and the reduction of the task to its true dimension.
//
// Closed loop (paper eq. 5–6): ΔS_out[k] = S* − S_out[k];  φ[k+1] = φ[k] + Δφ[k], with Δφ from
// the linear model J Δφ = ΔS_out (paper eq. 3).
//
// Loop modes (which S_out enters the error):
//   kModel     S_out = f(φ; S_in measured): the controller computes the output from the model
//              (the paper: "the output polarimeter is optional").
//   kMeasured  S_out = the output polarimeter's reading, which lags the command by the loop
//              delay. The Jacobian is still the model's, at the controller's φ.
//
// Task reduction (exact, no SVD), in the input frame. M is orthogonal, so J and J′ = MᵀJ have
// the same singular values, J⁺ = J′⁺Mᵀ and I − J⁺J = I − J′⁺J′. Every column of J′ = [Ω′_c × S_in]
// is ⊥ S_in, so with a right-handed tangent basis (e1, e2, S_in) at the measured input:
//   J′ = E·T,  E = [e1 e2],  T = EᵀJ′ = [e2ᵀΩ′; −e1ᵀΩ′] (2 × n),  J⁺ΔS = T⁺ EᵀMᵀΔS.
// For a point target the task is (T, e = Eᵀ(MᵀS* − MᵀS_out)), dimension 2, where MᵀS_out is
// S_in itself in model mode. Every law built on J⁺, Jᵀ or Jᵀ(JJᵀ + λI)⁻¹ gets the same Δφ from it
// as from (J, ΔS): JᵀΔS = TᵀEᵀMᵀΔS and Jᵀ(JJᵀ + λI)⁻¹ = Tᵀ(TTᵀ + λI)⁻¹EᵀMᵀ on the tangent plane.
// Taking the basis at S_in rather than S_out keeps its division off the control loop's critical
// path (S_in is known before the chain is evaluated).
// For a set target n·S = c the task is 1-D: a = nᵀJ = (S_in × Mᵀn)ᵀΩ′ (1 × n), e = c − n·S_out.

#include "dpc/control/controller_config.h"
#include "dpc/control/target.h"
#include "dpc/optics/waveplate_chain.h"

namespace dpc {

/// A d × n task Jacobian, d ≤ 3 (2 for a point target in tangent coordinates, 1 for a set).
/// Row-major: each row is contiguous, which is how the laws read it.
using TaskJacobian =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor, 3, kMaxControls>;
using TaskVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;

struct ControlProblem {
  // ---- Inputs, set by the caller.
  const WaveplateChain* chain = nullptr;  ///< the device model
  const Target* target = nullptr;
  const ChainPose* pose = nullptr;        ///< the chain at the controller's φ (pose->phi)
  StokesVector s_in = StokesVector::UnitX();            ///< measured input SOP
  StokesVector s_out_measured = StokesVector::UnitX();  ///< measured output SOP
  LoopMode loop_mode = LoopMode::kModel;
  /// Whether kinematics.jacobian (the full 3 × n J) is needed; the reduced task is always
  /// built. Set from ControlLaw::needs_jacobian().
  bool need_jacobian = true;

  // ---- Derived by UpdateControlProblem.
  ChainKinematics kinematics;     ///< model S_out, M, Ω′ (Ω and J if need_jacobian)
  StokesVector s_out_for_error;   ///< model or measured S_out, per loop_mode
  Vector3 tangent_e1, tangent_e2; ///< right-handed tangent basis at S_in (input frame)
  TaskJacobian task_jacobian;     ///< T (2 × n, point) or nᵀJ (1 × n, set)
  TaskVector task_error;          ///< Eᵀ Mᵀ(S* − S_out) or c − n·S_out

  const ControlVector& phi() const { return pose->phi; }
  int control_count() const { return static_cast<int>(pose->phi.size()); }
  /// Full 3-D error S* − S_out for a point target (paper eq. 5).
  Vector3 PointError() const { return target->point() - s_out_for_error; }
};

/// Real-time. Evaluates the chain at problem->pose and s_in, picks the S_out for the error by
/// loop mode, and builds the reduced task. The inputs must be set.
void UpdateControlProblem(ControlProblem* problem);

/// Real-time. The change of the task error when the input SOP moves by `ds_in` (input frame)
/// with φ fixed, to first order: −A·ds_in, A the error's linear map of S_in (Eᵀ for a point
/// target, (Mᵀn)ᵀ for a set). After UpdateControlProblem. Used for the delay compensator's
/// lead and for the rate that cancels a moving input (the DDS controller's rate commands).
inline void TaskErrorChangeOfInput(const ControlProblem& problem, const Vector3& ds_in, TaskVector* out) {
  if (problem.target->is_point()) {
    // e = Eᵀ(MᵀS* − S_in).
    out->resize(2);
    (*out)[0] = -problem.tangent_e1.dot(ds_in);
    (*out)[1] = -problem.tangent_e2.dot(ds_in);
  } else {
    // e = c − n·(M S_in).
    out->resize(1);
    (*out)[0] = -(problem.kinematics.mueller.transpose() * problem.target->normal()).dot(ds_in);
  }
}

/// Real-time. The task Jacobian of `target` for kinematics `k` evaluated at input `s_in`, with
/// (e1, e2) the tangent basis at s_in (TangentBasis).
void BuildTaskJacobian(const Target& target, const ChainKinematics& k, const StokesVector& s_in,
                       const Vector3& e1, const Vector3& e2, TaskJacobian* task_jacobian);

}  // namespace dpc
