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

const StokesVector& DelayCompensator::Predict(const StokesVector& s_in_measured,
                                              double horizon_samples) {
  predictor_.Observe(s_in_measured);
  return Keep(predictor_.PredictSamples(horizon_samples));
}

const StokesVector& DelayCompensator::PredictAt(const StokesVector& s_in_measured, double t_s,
                                                double horizon_s) {
  predictor_.ObserveAt(s_in_measured, t_s);
  return Keep(predictor_.PredictSeconds(horizon_s));
}

const StokesVector& DelayCompensator::Keep(const StokesVector& prediction) {
  previous_ = have_previous_ ? current_ : prediction;
  have_previous_ = true;
  current_ = prediction;
  return current_;
}

void DelayCompensator::AddLead(ControlProblem* problem) const {
  if (lead_samples_ == 0.0) return;
  const Vector3 motion = current_ - previous_;
  if (problem->target->is_point()) {
    // e = Eᵀ(MᵀS* − S_in): m = −Eᵀ·motion.
    problem->task_error[0] -= lead_samples_ * problem->tangent_e1.dot(motion);
    problem->task_error[1] -= lead_samples_ * problem->tangent_e2.dot(motion);
  } else {
    // e = c − n·(M S_in): m = −(Mᵀn)·motion.
    const Vector3 normal_in = problem->kinematics.mueller.transpose() * problem->target->normal();
    problem->task_error[0] -= lead_samples_ * normal_in.dot(motion);
  }
}

}  // namespace dpc
