// TargetFromRequest (bus/message_conversion.h) on any TargetRequest payload a peer can send: it
// documents std::invalid_argument (ScenarioError is one) for a bad request; anything else that
// escapes is a crash.
#include <cstdint>
#include <stdexcept>

#include "dpc/bus/message_conversion.h"
#include "fuzz_wire.h"
#include "target_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dpc;
  msg::TargetRequest message;
  if (!fuzz::FromWire(data, size, &message)) return 0;
  TargetConfig target;
  try {
    target = bus::TargetFromRequest(message);
  } catch (const std::invalid_argument&) {
    return 0;  // refused, as documented
  }
  fuzz::CheckAcceptedTarget(target);
  return 0;
}
