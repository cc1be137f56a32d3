#pragma once
// Chooses a control law by configuration.
//
//   method      law                                      uses
//   inverse     InverseJacobianLaw                       step
//   transpose   TransposeJacobianLaw                     step
//   damped      DampedJacobianLaw                        step, damping
//   pinv        PseudoInverseLaw                         step, singular_value_tolerance
//   rls         RegularizedLeastSquaresLaw               step, damping
//   gp          GradientProjectionLaw                    step, nullspace_step,
//                                                        singular_value_tolerance,
//                                                        singularity_damping, nullspace_criterion,
//                                                        curvature_correction
//   gpt         GradientProjectionLaw with threshold     the same and threshold
//   extended    ExtendedJacobianLaw                      step, nullspace_step
//   dither      DitheringLaw                             step, dither.* (with the loop timing)

#include <functional>
#include <memory>

#include "dpc/control/control_law.h"
#include "dpc/control/controller_config.h"
#include "dpc/control/dithering_law.h"

namespace dpc {

/// The dithering law's sample counts from its config and the loop timing:
///   settle_samples = dither.settle_samples, or the loop delay in samples when it is 0;
///   reset_samples  = max(1, round(reset_duration_s · sample_rate_hz)).
/// Sample counts saturate at INT_MAX (validation keeps them ≤ 1e7).
DitherSettings BuildDitherSettings(const DitherConfig& dither, const LawTiming& timing);

/// Builds the configured law (config.method with the settings it uses, see the table above)
/// for a task of `control_count` controls and a point or set target. Throws
/// std::invalid_argument when the parameters are invalid or the method does not fit (inverse
/// and damped need a square task: 3 controls with a point target, or 1 control with a set
/// target).
std::unique_ptr<ControlLaw> MakeControlLaw(const ControllerConfig& config, const LawTiming& timing,
                                           int control_count, bool point_target);

/// Builds the control law of a loop: MakeControlLaw by default; control engineers pass their
/// own to run a law of theirs (any ControlLaw) in the simulator or the DDS controller.
using ControlLawFactory = std::function<std::unique_ptr<ControlLaw>(
    const ControllerConfig&, const LawTiming&, int control_count, bool point_target)>;

}  // namespace dpc
