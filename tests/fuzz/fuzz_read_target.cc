// ReadTarget (bus/message_conversion.h) on any Target payload a peer can send.
#include <cstdint>

#include "dpc/bus/message_conversion.h"
#include "fuzz_wire.h"
#include "target_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dpc;
  msg::Target message;
  if (!fuzz::FromWire(data, size, &message)) return 0;
  BenchTarget out;
  if (!bus::ReadTarget(message, &out).empty()) return 0;
  fuzz::CheckAcceptedTarget(out.target);
  DPC_FUZZ_CHECK(out.revision == message.revision() && out.request_id == message.request_id().to_string(),
                 "contract", "revision / request_id not copied");
  DPC_FUZZ_CHECK(out.request_id.size() <= 64, "idl-bound", "request_id of %zu characters", out.request_id.size());
  return 0;
}
