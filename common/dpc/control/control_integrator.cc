#include "dpc/control/control_integrator.h"

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
  if (!IsUsable(status) || delta_phi.size() != phi_.size() || !delta_phi.allFinite()) {
    ++rejected_;
    return Outcome::kRejected;
  }
  phi_ += delta_phi;
  if (chain_.ClampToRanges(&phi_) > 0) {
    ++clamped_;
    return Outcome::kClamped;
  }
  return Outcome::kApplied;
}

}  // namespace dpc
