// ReadSummary (bus/message_conversion.h) on any BenchSummary payload a peer can send: what
// `dpc dashboard` shows of the bench must be finite, unit where it is a Stokes vector, and
// bounded, whatever arrives.
#include <cmath>
#include <cstdint>

#include "dpc/bus/message_conversion.h"
#include "fuzz_wire.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dpc;
  msg::BenchSummary message;
  if (!fuzz::FromWire(data, size, &message)) return 0;

  BenchSummary out;
  const std::string reason = bus::ReadSummary(message, &out);
  BenchSummary reused;
  reused.trail.assign(300, {9, 9, 9, 9, 9, 9});
  reused.error_mean_deg = 99.0;
  reused.state = DriverState{};
  const std::string reused_reason = bus::ReadSummary(message, &reused);
  DPC_FUZZ_CHECK(reason == reused_reason, "contract", "a reused output changes the verdict: \"%s\" vs \"%s\"",
                 reason.c_str(), reused_reason.c_str());
  if (!reason.empty()) return 0;

  const double figures[] = {out.period_s, out.error_max_deg, out.latency_p50_us, out.latency_p90_us,
                            out.latency_p99_us, out.latency_max_us, out.error_mean_deg.value_or(0.0)};
  for (double v : figures) DPC_FUZZ_CHECK(std::isfinite(v) && v >= 0.0, "non-finite", "accepted a figure %g", v);
  DPC_FUZZ_CHECK(out.trail.size() <= kMaxSummaryTrailPoints, "idl-bound", "accepted %zu trail points",
                 out.trail.size());
  DPC_FUZZ_CHECK(reused.trail.size() == out.trail.size(), "contract", "a reused output keeps stale trail points");
  for (const auto& p : out.trail) {
    for (int k = 0; k < 2; ++k) {
      const double norm = std::sqrt(p[3 * k] * p[3 * k] + p[3 * k + 1] * p[3 * k + 1] + p[3 * k + 2] * p[3 * k + 2]);
      DPC_FUZZ_CHECK(std::abs(norm - 1.0) <= 1e-6, "non-unit", "accepted a trail point of |S| = %g", norm);
    }
  }
  if (out.last_sample != 0) {
    DPC_FUZZ_CHECK(std::abs(out.s_in.norm() - 1.0) <= 1e-6 && std::abs(out.s_out.norm() - 1.0) <= 1e-6, "non-unit",
                   "accepted a non-unit S_in or S_out");
  }
  DPC_FUZZ_CHECK(out.state.has_value() == message.state_known() && reused.state.has_value() == out.state.has_value(),
                 "contract", "the state's presence not as the message says");
  if (out.state) {
    DPC_FUZZ_CHECK(out.state->control_count() <= static_cast<int>(msg::MAX_CONTROLS), "idl-bound", "%d controls",
                   out.state->control_count());
    DPC_FUZZ_CHECK(fuzz::AllFiniteVector(out.state->motion.phi), "non-finite", "accepted a non-finite φ");
    DPC_FUZZ_CHECK(out.state->mode == DriverMode::kActive || out.state->mode == DriverMode::kHolding, "out-of-range",
                   "mode %d", static_cast<int>(out.state->mode));
  }
  return 0;
}
