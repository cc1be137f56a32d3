#include "dpc/control/delay_compensator.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace dpc {

double IntegratorLagSamples(double step) {
  if (!(step > 0.0) || !std::isfinite(step)) return 0.0;
  return step >= 1.0 ? 0.0 : (1.0 - step) / step;
}

DelayCompensator::DelayCompensator(double window_samples, double lead_samples,
                                   double nominal_sample_period_s)
    : predictor_(window_samples, nominal_sample_period_s), lead_samples_(lead_samples) {
  if (!std::isfinite(lead_samples) || lead_samples < 0.0) {
    throw std::invalid_argument(
        fmt::format("delay compensation lead must be >= 0 samples (got {})", lead_samples));
  }
}

void DelayCompensator::Reset() {
  predictor_.Reset();
  have_previous_ = false;
}

const StokesVector& DelayCompensator::PredictAt(const StokesVector& s_in_measured, double t_s,
                                                double horizon_s) {
  predictor_.ObserveAt(s_in_measured, t_s);
  return Keep(predictor_.PredictSeconds(horizon_s));
}

}  // namespace dpc
