#include "dpc/control/dithering_law.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace dpc {

DitheringLaw::DitheringLaw(double step, const DitherSettings& settings)
    : step_(step), settings_(settings) {
  if (!std::isfinite(step) || !(step > 0.0)) {
    throw std::invalid_argument(fmt::format("dither step must be > 0 (got {})", step));
  }
  if (!std::isfinite(settings.amplitude) || !(settings.amplitude > 0.0)) {
    throw std::invalid_argument(
        fmt::format("dither amplitude must be > 0 (got {})", settings.amplitude));
  }
  if (settings.settle_samples < 1) {
    throw std::invalid_argument(
        fmt::format("dither settle_samples must be >= 1 (got {})", settings.settle_samples));
  }
  if (!std::isfinite(settings.reset_threshold) || !(settings.reset_threshold > 0.0)) {
    throw std::invalid_argument(
        fmt::format("dither reset_threshold must be > 0 (got {})", settings.reset_threshold));
  }
  if (settings.reset_samples < 1) {
    throw std::invalid_argument(
        fmt::format("dither reset_samples must be >= 1 (got {})", settings.reset_samples));
  }
}

void DitheringLaw::Activate(const ControlVector& phi) {
  base_ = phi;
  command_ = phi;
  cost_plus_.setZero(phi.size());
  cost_minus_.setZero(phi.size());
  phase_ = Phase::kProbe;
  StartProbe(0);
}

void DitheringLaw::StartProbe(int probe) {
  probe_ = probe;
  command_ = base_;
  command_[probe / 2] += (probe % 2 == 0 ? 1.0 : -1.0) * settings_.amplitude;
  wait_ = settings_.settle_samples;
}

bool DitheringLaw::StartResetIfNeeded(const WaveplateChain& chain) {
  for (int c = 0; c < base_.size(); ++c) {
    if (std::abs(base_[c]) <= settings_.reset_threshold) continue;
    const ControlChannel& channel = chain.controls()[c];
    const double theta = channel.map.AngleRad(base_[c]);
    // Wind back towards zero by one full turn of the angle.
    const double slope = channel.map.DerivativeRadPerUnit(base_[c]);
    const double direction = (base_[c] > 0.0) == (slope > 0.0) ? -1.0 : 1.0;
    const double span = 4.0 * settings_.reset_threshold + 8.0 * M_PI / std::abs(slope);
    const double lo = channel.range ? channel.range->min : base_[c] - span;
    const double hi = channel.range ? channel.range->max : base_[c] + span;
    const auto target = channel.map.ControlForAngle(theta + direction * 2.0 * M_PI, lo, hi);
    if (!target) continue;
    reset_control_ = c;
    reset_from_ = base_[c];
    reset_to_ = *target;
    reset_step_ = 0;
    command_ = base_;
    phase_ = Phase::kReset;
    ++diagnostics_.resets;
    return true;
  }
  return false;
}

ControlStatus DitheringLaw::ComputeUpdate(const ControlProblem& problem,
                                          ControlVector* delta_phi) {
  const int n = problem.control_count();
  if (base_.size() != n) Activate(problem.phi());
  diagnostics_.rank = 0;
  diagnostics_.loop_suspended = phase_ == Phase::kReset;
  diagnostics_.nullspace_active = false;

  if (phase_ == Phase::kReset) {
    ++reset_step_;
    const double t = static_cast<double>(reset_step_) / settings_.reset_samples;
    command_[reset_control_] = reset_from_ + (reset_to_ - reset_from_) * std::min(t, 1.0);
    if (reset_step_ >= settings_.reset_samples) {
      base_[reset_control_] = reset_to_;
      phase_ = Phase::kProbe;
      if (!StartResetIfNeeded(*problem.chain)) StartProbe(0);
    }
  } else if (--wait_ <= 0) {
    const double cost = problem.target->LeakFraction(problem.s_out_measured);
    (probe_ % 2 == 0 ? cost_plus_ : cost_minus_)[probe_ / 2] = cost;
    if (probe_ + 1 < 2 * n) {
      StartProbe(probe_ + 1);
    } else {
      base_ -= (step_ / (2.0 * settings_.amplitude)) * (cost_plus_ - cost_minus_);
      problem.chain->ClampToRanges(&base_);
      if (!StartResetIfNeeded(*problem.chain)) StartProbe(0);
    }
  }
  *delta_phi = command_ - problem.phi();
  if (!delta_phi->allFinite()) {
    delta_phi->setZero(n);
    return ControlStatus::kNotFinite;
  }
  return ControlStatus::kOk;
}

}  // namespace dpc
