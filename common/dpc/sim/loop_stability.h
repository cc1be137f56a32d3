#pragma once
// Stability of the sampled control loop with a command delay of D samples.
//
// Linearized near lock, every pseudo-inverse-type law (pinv, gp, gpt, rls with small λ,
// extended) corrects a fraction μ (the step) of the tangent error per sample:
//
//  * Loop mode "model": the controller computes S_out = f(φ; S_in) from its own latest command,
//    so its internal loop has no delay: e[k+1] = (1 − μ) e[k]. Stable for 0 < μ < 2 whatever the
//    delay; the delay only costs tracking error (the input moves by ω·D·dt while a command is in
//    flight, ≈ 5.7° at the paper's 100 krad/s and 1 µs).
//  * Loop mode "measured": the controller sees S_out through the D-sample delay, so
//    φ[k+1] = φ[k] − μ·(φ[k+1−D] − φ*), characteristic polynomial z^D − z^(D−1) + μ. It is stable
//    iff 0 < μ < μ_max(D) = 2·sin(π / (2(2D − 1)))   (Levin & May 1976), i.e. μ < 2 for D = 1,
//    μ < 1 for D = 2 and μ_max ≈ π/(2D) for large D. The paper's D = 50 (1 µs at 50 MHz) gives
//    μ_max = 0.0317: its step 0.1 would oscillate in this mode.
//  * The transpose law's gain is μ·σ² (σ the singular values of J) instead of μ.

#include <cstdint>
#include <string>
#include <vector>

#include "dpc/config/scenario_config.h"

namespace dpc {

/// μ_max(D) = 2 sin(π / (2(2D − 1))) for the measured loop; D ≥ 1 (throws otherwise).
double MeasuredLoopStepLimit(int64_t delay_samples);

/// Human-readable warnings for a valid scenario that will probably not behave as intended
/// (e.g. a measured loop with a step above μ_max). Empty when nothing looks wrong.
std::vector<std::string> ScenarioWarnings(const ScenarioConfig& scenario);

}  // namespace dpc
