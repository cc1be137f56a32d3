#pragma once
// The Jacobian J = ∂S_out/∂φ by central finite differences of the forward kinematics:
//
//   J_c ≈ [f(φ + h e_c; S_in) − f(φ − h e_c; S_in)] / (2h)       (error O(h²))
//
// Needs no derivative of any stage map, so it serves chains whose maps have none and checks the
// closed-form Jacobian (WaveplateChain::Evaluate). 2n forward passes: not for the real-time path.

#include "dpc/optics/waveplate_chain.h"

namespace dpc {

/// Default step: balances truncation O(h²) against round-off O(ε/h) for θ ≈ π·φ.
inline constexpr double kNumericJacobianStep = 1e-6;

/// Throws std::invalid_argument if `phi` has the wrong size or `step` is not positive.
Matrix3X NumericJacobian(const WaveplateChain& chain, const ControlVector& phi,
                         const StokesVector& s_in, double step = kNumericJacobianStep);

}  // namespace dpc
