// ReadCommand (bus/message_conversion.h) on any WaveplateCommand payload a peer can send, for a
// device of 1 … kMaxControls controls (chosen by the message's sequence number).
#include <cstdint>
#include <limits>

#include "dpc/bus/message_conversion.h"
#include "fuzz_wire.h"

namespace {

/// An output as a driver reuses it: sized, filled and named by an earlier command.
dpc::ControllerCommand Dirty() {
  dpc::ControllerCommand out;
  out.controller_id = std::string(200, 'x');
  out.priority = -7;
  out.sequence = out.answers_sample = 77;
  out.sample_time_ns = out.sample_publish_time_ns = out.publish_time_ns = -77;
  out.phi = dpc::ControlVector::Constant(dpc::kMaxControls, std::numeric_limits<double>::quiet_NaN());
  out.rate_per_s = out.phi;
  return out;
}

bool Same(const dpc::ControllerCommand& a, const dpc::ControllerCommand& b) {
  return a.controller_id == b.controller_id && a.priority == b.priority && a.sequence == b.sequence &&
         a.answers_sample == b.answers_sample && a.sample_time_ns == b.sample_time_ns &&
         a.sample_publish_time_ns == b.sample_publish_time_ns && a.publish_time_ns == b.publish_time_ns &&
         a.phi.size() == b.phi.size() && a.phi == b.phi && a.rate_per_s.size() == b.rate_per_s.size() &&
         a.rate_per_s == b.rate_per_s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dpc;
  msg::WaveplateCommand message;
  if (!fuzz::FromWire(data, size, &message)) return 0;
  const int controls = fuzz::ControlCountFor(message.sequence_number());

  ControllerCommand out;
  const std::string reason = bus::ReadCommand(message, controls, &out);
  ControllerCommand reused = Dirty();
  const std::string reused_reason = bus::ReadCommand(message, controls, &reused);
  DPC_FUZZ_CHECK(reason == reused_reason, "contract", "a reused output changes the verdict: \"%s\" vs \"%s\"",
                 reason.c_str(), reused_reason.c_str());
  // Read even when refused (for the report).
  DPC_FUZZ_CHECK(out.controller_id == message.controller_id().to_string() &&
                     reused.controller_id == out.controller_id &&
                     out.answers_sample == message.answers_sample() &&
                     reused.answers_sample == out.answers_sample,
                 "contract", "controller_id / answers_sample not read");
  if (!reason.empty()) return 0;

  // Accepted: a controller id, one finite φ per control, rates empty or one finite per control.
  DPC_FUZZ_CHECK(!out.controller_id.empty(), "contract", "accepted an empty controller_id");
  DPC_FUZZ_CHECK(out.controller_id.size() <= 64, "idl-bound", "controller_id of %zu characters",
                 out.controller_id.size());
  DPC_FUZZ_CHECK(out.phi.size() == controls, "out-of-range", "accepted %d φ for %d controls",
                 static_cast<int>(out.phi.size()), controls);
  DPC_FUZZ_CHECK(message.phi().size() <= msg::MAX_CONTROLS &&
                     message.phi_rate_per_s().size() <= msg::MAX_CONTROLS,
                 "idl-bound", "accepted %zu φ and %zu rates (MAX_CONTROLS %u)", message.phi().size(),
                 message.phi_rate_per_s().size(), msg::MAX_CONTROLS);
  DPC_FUZZ_CHECK(out.rate_per_s.size() == 0 || out.rate_per_s.size() == controls, "out-of-range",
                 "accepted %d rates for %d controls", static_cast<int>(out.rate_per_s.size()), controls);
  DPC_FUZZ_CHECK(fuzz::AllFiniteVector(out.phi) && fuzz::AllFiniteVector(out.rate_per_s), "non-finite",
                 "accepted a non-finite φ or rate");
  DPC_FUZZ_CHECK(out.priority == message.priority() && out.sequence == message.sequence_number() &&
                     out.sample_time_ns == message.sample_time_ns() &&
                     out.sample_publish_time_ns == message.sample_publish_time_ns() &&
                     out.publish_time_ns == message.publish_time_ns(),
                 "contract", "accepted command not copied field for field");
  for (int i = 0; i < controls; ++i) {
    DPC_FUZZ_CHECK(out.phi[i] == message.phi()[static_cast<size_t>(i)], "contract", "φ[%d] not copied", i);
  }
  DPC_FUZZ_CHECK(Same(out, reused), "contract", "a reused output keeps stale values");
  return 0;
}
