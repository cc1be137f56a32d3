#include "dpc/disturbance/disturbance_factory.h"

#include <fmt/format.h>

#include <optional>
#include <stdexcept>

#include "dpc/disturbance/constant_rotation_disturbance.h"
#include "dpc/disturbance/paper_scrambler.h"
#include "dpc/disturbance/random_walk_disturbance.h"
#include "dpc/disturbance/transient_burst_disturbance.h"

namespace dpc {

std::unique_ptr<Disturbance> MakeDisturbance(const DisturbanceConfig& config,
                                             double sample_rate_hz) {
  using Kind = DisturbanceConfig::Kind;
  switch (config.kind) {
    case Kind::kPaperScrambler:
      return std::make_unique<PaperScrambler>(config.rate_rad_per_s, config.kick_rms_ratio,
                                              config.axis, config.kick_axis, sample_rate_hz);
    case Kind::kRandomWalk:
      return std::make_unique<RandomWalkDisturbance>(config.diffusion_rad_per_sqrt_s,
                                                     sample_rate_hz);
    case Kind::kConstantRotation:
      return std::make_unique<ConstantRotationDisturbance>(config.rate_rad_per_s, config.axis,
                                                           sample_rate_hz);
    case Kind::kTransientBurst:
      return std::make_unique<TransientBurstDisturbance>(
          config.start_s, config.duration_s, config.rate_rad_per_s, config.period_s,
          config.envelope,
          config.random_axis ? std::nullopt : std::optional<Vector3>(config.axis),
          sample_rate_hz);
  }
  throw std::invalid_argument(
      fmt::format("disturbance: unknown kind {}", static_cast<int>(config.kind)));
}

}  // namespace dpc
