#include "dpc/control/control_integrator.h"

#include "dpc/optics/count_dispatch.h"

#include <fmt/format.h>

#include <stdexcept>

namespace dpc {

ControlIntegrator::ControlIntegrator(const WaveplateChain& chain, const ControlVector& initial_phi)
    : chain_(chain) {
  Reset(initial_phi);
}

void ControlIntegrator::Reset(const ControlVector& phi) {
  if (phi.size() != chain_.control_count()) {
    throw std::invalid_argument(fmt::format("initial control vector has {} values; the chain has "
                                            "{} controls",
                                            phi.size(), chain_.control_count()));
  }
  if (!phi.allFinite()) {
    throw std::invalid_argument("initial control vector is not finite");
  }
  phi_ = phi;
  chain_.ClampToRanges(&phi_);
}

ControlIntegrator::Outcome ControlIntegrator::Apply(ControlStatus status,
                                                    const ControlVector& delta_phi) {
  if (!IsUsable(status) || delta_phi.size() != phi_.size()) {
    ++rejected_;
    return Outcome::kRejected;
  }
  const int n = static_cast<int>(phi_.size());
  const bool finite = DispatchCount(n, [&](auto fixed) {
    const int count = FixedOr(fixed, n);
    const double* delta = delta_phi.data();
    double probe = 0.0;  // 0·x is 0 for finite x, NaN for NaN and ±Inf
    for (int i = 0; i < count; ++i) probe += 0.0 * delta[i];
    if (probe != 0.0) return false;
    double* phi = phi_.data();
    for (int i = 0; i < count; ++i) phi[i] += delta[i];
    return true;
  });
  if (!finite) {
    ++rejected_;
    return Outcome::kRejected;
  }
  if (chain_.ClampToRanges(&phi_) > 0) {
    ++clamped_;
    return Outcome::kClamped;
  }
  return Outcome::kApplied;
}

}  // namespace dpc
