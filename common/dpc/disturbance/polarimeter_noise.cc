#include "dpc/disturbance/polarimeter_noise.h"

#include <cmath>

#include "dpc/disturbance/disturbance.h"

namespace dpc {

PolarimeterNoise::PolarimeterNoise(double sigma_deg, uint64_t seed, uint64_t stream)
    : sigma_deg_(sigma_deg), sigma_rad_(sigma_deg * M_PI / 180.0), random_(seed, stream) {
  RequireNonNegativeFinite(sigma_deg, "polarimeter noise: sigma_deg");
}

}  // namespace dpc
