#pragma once
// The one small interface every control law implements (the paper's section III methods, the
// extended Jacobian, and the dithering baseline). Callers pick a law by configuration
// (control_law_factory.h) and swap laws freely.
//
// Real-time contract: ComputeUpdate runs once per sample in the control loop. It must not
// allocate, lock or block; all scratch storage is sized at construction. Activate and the
// constructors run outside the loop and may allocate.

#include <cstdint>
#include <string_view>

#include "dpc/control/control_problem.h"
#include "dpc/control/singular_values.h"

namespace dpc {

/// Outcome of one update. Positive: degraded but usable (apply Δφ). Negative: failed; the
/// caller must not apply Δφ (it is set to zero).
enum class ControlStatus : int {
  kOk = 0,
  kRankDeficient = 1,  ///< the task Jacobian lost rank; Δφ is the pseudo-inverse's best effort
  kSingular = -1,      ///< the law needs an inverse that does not exist here
  kNotFinite = -2,     ///< NaN or Inf in the problem or the result
};

inline bool IsUsable(ControlStatus status) { return static_cast<int>(status) >= 0; }
std::string_view ControlStatusName(ControlStatus status);

/// Diagnostics of the last update (read by the simulator's statistics and the status topic).
struct ControlDiagnostics {
  int rank = 0;               ///< numerical rank of the task Jacobian
  /// Singular values of the task Jacobian (= those of J), evaluated when read.
  SingularValues singular_values;
  bool nullspace_active = false;  ///< the null-space term was applied this sample
  bool loop_suspended = false;    ///< the law did not regulate this sample (dither probe/reset)
  int64_t resets = 0;             ///< control resets so far (dithering baseline)
};

class ControlLaw {
 public:
  virtual ~ControlLaw() = default;

  /// Not real-time. Called when control starts (or restarts) from the control vector `phi` that
  /// the device currently applies; laws with internal state start from it (bumpless start).
  virtual void Activate(const ControlVector& phi) { (void)phi; }

  /// Real-time. Computes Δφ (size n) for the problem at the current sample. On a negative
  /// status Δφ is zero and must not be applied.
  virtual ControlStatus ComputeUpdate(const ControlProblem& problem, ControlVector* delta_phi) = 0;

  /// Short name as on the command line ("gp", "pinv", …).
  virtual std::string_view name() const = 0;

  /// Whether ComputeUpdate reads problem.kinematics.jacobian (the full 3 × n J). Laws that work
  /// on the reduced task only return false, which saves computing J on every sample.
  virtual bool needs_jacobian() const { return true; }

  const ControlDiagnostics& diagnostics() const { return diagnostics_; }

 protected:
  ControlDiagnostics diagnostics_;
};

}  // namespace dpc
