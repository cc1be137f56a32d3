#pragma once
// Builds the disturbance a DisturbanceConfig names (scenario.proto Disturbance), so callers
// choose a disturbance by configuration.
//
//   kPaperScrambler   → PaperScrambler(rate_rad_per_s, kick_rms_ratio, axis, kick_axis)
//   kRandomWalk       → RandomWalkDisturbance(diffusion_rad_per_sqrt_s)
//   kConstantRotation → ConstantRotationDisturbance(rate_rad_per_s, axis)
//   kTransientBurst   → TransientBurstDisturbance(start_s, duration_s, rate_rad_per_s (peak),
//                       period_s, envelope, random_axis ? random per burst : axis)
//
// Fields that do not apply to the kind are ignored.

#include <memory>

#include "dpc/config/scenario_config.h"
#include "dpc/disturbance/disturbance.h"

namespace dpc {

/// Not real-time. Throws std::invalid_argument for an unknown kind or whatever the chosen
/// constructor rejects (its message names the field).
std::unique_ptr<Disturbance> MakeDisturbance(const DisturbanceConfig& config,
                                             double sample_rate_hz);

}  // namespace dpc
