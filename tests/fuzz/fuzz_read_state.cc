// ReadState (bus/message_conversion.h) on any WaveplateState payload a peer can send, for a
// device of 1 … kMaxControls controls (chosen by the message's sequence number).
#include <cmath>
#include <cstdint>
#include <limits>

#include "dpc/bus/message_conversion.h"
#include "fuzz_wire.h"

namespace {

/// An output as a controller reuses it: sized, filled and named by an earlier state.
dpc::DriverState Dirty() {
  dpc::DriverState out;
  out.sequence = out.answers_sample = 77;
  out.sample_time_ns = out.sample_publish_time_ns = out.command_receive_time_ns = out.publish_time_ns = -77;
  out.motion.phi = dpc::ControlVector::Constant(dpc::kMaxControls, std::numeric_limits<double>::quiet_NaN());
  out.motion.rate_per_s = out.motion.phi;
  out.motion.start_ns = -5;
  out.motion.end_ns = 5;
  out.motion.moving = true;
  out.saturated.fill(true);
  out.mode = dpc::DriverMode::kActive;
  out.reason = out.obeyed_controller_id = out.last_rejection = std::string(300, 'x');
  out.obeyed_priority = -7;
  out.commands_applied = out.commands_rejected = out.commands_limited = out.controller_switches = 77;
  return out;
}

bool Same(const dpc::DriverState& a, const dpc::DriverState& b) {
  const dpc::WaveplateMotion& m = a.motion;
  const dpc::WaveplateMotion& n = b.motion;
  return a.sequence == b.sequence && a.answers_sample == b.answers_sample &&
         a.sample_time_ns == b.sample_time_ns && a.sample_publish_time_ns == b.sample_publish_time_ns &&
         a.command_receive_time_ns == b.command_receive_time_ns && a.publish_time_ns == b.publish_time_ns &&
         m.phi.size() == n.phi.size() && m.phi == n.phi && m.rate_per_s.size() == n.rate_per_s.size() &&
         m.rate_per_s == n.rate_per_s && m.start_ns == n.start_ns && m.end_ns == n.end_ns &&
         m.moving == n.moving && a.saturated == b.saturated && a.mode == b.mode && a.reason == b.reason &&
         a.obeyed_controller_id == b.obeyed_controller_id && a.obeyed_priority == b.obeyed_priority &&
         a.commands_applied == b.commands_applied && a.commands_rejected == b.commands_rejected &&
         a.commands_limited == b.commands_limited && a.controller_switches == b.controller_switches &&
         a.last_rejection == b.last_rejection;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dpc;
  msg::WaveplateState message;
  if (!fuzz::FromWire(data, size, &message)) return 0;
  const int controls = fuzz::ControlCountFor(message.sequence_number());

  DriverState out;
  const std::string reason = bus::ReadState(message, controls, &out);
  DriverState reused = Dirty();
  const std::string reused_reason = bus::ReadState(message, controls, &reused);
  DPC_FUZZ_CHECK(reason == reused_reason, "contract", "a reused output changes the verdict: \"%s\" vs \"%s\"",
                 reason.c_str(), reused_reason.c_str());
  if (!reason.empty()) return 0;

  // Accepted: one finite φ per control, rates empty or one finite per control, a known mode, a
  // ramp of at most kMaxStateRampNs.
  const WaveplateMotion& motion = out.motion;
  DPC_FUZZ_CHECK(out.control_count() == controls && motion.rate_per_s.size() == controls, "out-of-range",
                 "accepted %d φ, %d rates for %d controls", out.control_count(),
                 static_cast<int>(motion.rate_per_s.size()), controls);
  DPC_FUZZ_CHECK(message.phi_applied().size() <= msg::MAX_CONTROLS &&
                     message.phi_rate_per_s().size() <= msg::MAX_CONTROLS &&
                     message.saturated().size() <= msg::MAX_CONTROLS,
                 "idl-bound", "accepted %zu phi_applied, %zu rates, %zu saturated (MAX_CONTROLS %u)",
                 message.phi_applied().size(), message.phi_rate_per_s().size(), message.saturated().size(),
                 msg::MAX_CONTROLS);
  DPC_FUZZ_CHECK(fuzz::AllFiniteVector(motion.phi) && fuzz::AllFiniteVector(motion.rate_per_s), "non-finite",
                 "accepted a non-finite φ or rate");
  DPC_FUZZ_CHECK(out.mode == DriverMode::kActive || out.mode == DriverMode::kHolding, "out-of-range",
                 "mode %d", static_cast<int>(out.mode));
  DPC_FUZZ_CHECK(motion.end_ns >= motion.start_ns &&
                     static_cast<uint64_t>(motion.end_ns) - static_cast<uint64_t>(motion.start_ns) <=
                         kMaxStateRampNs,
                 "out-of-range", "accepted a ramp from %lld to %lld ns", static_cast<long long>(motion.start_ns),
                 static_cast<long long>(motion.end_ns));
  DPC_FUZZ_CHECK(!motion.moving || motion.end_ns > motion.start_ns, "out-of-range", "moving over no time");
  for (size_t i = static_cast<size_t>(controls); i < out.saturated.size(); ++i) {
    DPC_FUZZ_CHECK(!out.saturated[i], "contract", "saturated[%zu] set beyond %d controls", i, controls);
  }
  DPC_FUZZ_CHECK(out.reason.size() <= 256 && out.obeyed_controller_id.size() <= 64 &&
                     out.last_rejection.size() <= 256,
                 "idl-bound", "strings longer than their bounds");
  // The motion the state describes stays finite inside its ramp (what a controller and the
  // simulated bench evaluate).
  ControlVector at;
  motion.At(motion.start_ns, &at);
  DPC_FUZZ_CHECK(fuzz::AllFiniteVector(at), "motion-overflow", "φ(start) not finite");
  motion.At(motion.end_ns, &at);
  DPC_FUZZ_CHECK(fuzz::AllFiniteVector(at), "motion-overflow",
                 "accepted a state whose φ(ramp end) is not finite (φ + rate·%.9g s overflows)",
                 static_cast<double>(motion.end_ns - motion.start_ns) * 1e-9);
  DPC_FUZZ_CHECK(out.sequence == message.sequence_number() && out.answers_sample == message.answers_sample() &&
                     out.publish_time_ns == message.publish_time_ns() &&
                     out.obeyed_priority == message.obeyed_priority() &&
                     out.commands_rejected == message.commands_rejected() &&
                     out.reason == message.reason().to_string(),
                 "contract", "accepted state not copied field for field");
  DPC_FUZZ_CHECK(Same(out, reused), "contract", "a reused output keeps stale values");
  return 0;
}
