#include "dpc/disturbance/random_walk_disturbance.h"

#include <fmt/format.h>

#include <cmath>

namespace dpc {

RandomWalkDisturbance::RandomWalkDisturbance(double diffusion_rad_per_sqrt_s,
                                             double sample_rate_hz)
    : diffusion_rad_per_sqrt_s_(diffusion_rad_per_sqrt_s) {
  const double sample_period_s = SamplePeriodFromRate(sample_rate_hz, "random walk");
  RequireNonNegativeFinite(diffusion_rad_per_sqrt_s, "random walk: diffusion_rad_per_sqrt_s");
  step_sigma_rad_ = diffusion_rad_per_sqrt_s * std::sqrt(sample_period_s);
}

std::string RandomWalkDisturbance::Describe() const {
  return fmt::format("random walk: isotropic diffusion D = {:g} rad/sqrt(s) ({:g} rad per "
                     "component per sample)",
                     diffusion_rad_per_sqrt_s_, step_sigma_rad_);
}

}  // namespace dpc
