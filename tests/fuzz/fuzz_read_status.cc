// ReadStatus (bus/message_conversion.h) on any ControllerStatus payload a peer can send: what
// `dpc dashboard` and `dpc monitor` show of a controller must be finite, in range and free of
// control characters, whatever arrives.
#include <cmath>
#include <cstdint>
#include <string>

#include "dpc/bus/message_conversion.h"
#include "fuzz_wire.h"

namespace {
bool Printable(const std::string& text) {
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) return false;
  }
  return true;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dpc;
  msg::ControllerStatus message;
  if (!fuzz::FromWire(data, size, &message)) return 0;

  ControllerStatusReport out;
  const std::string reason = bus::ReadStatus(message, &out);
  if (!reason.empty()) return 0;
  const double figures[] = {out.error_deg, out.sigma_max, out.sigma_min, out.nullspace_active_fraction,
                            out.compute_time_mean_s, out.compute_time_max_s};
  for (double v : figures) DPC_FUZZ_CHECK(std::isfinite(v) && v >= 0.0, "non-finite", "accepted a figure %g", v);
  DPC_FUZZ_CHECK(out.error_deg <= 180.0, "out-of-range", "accepted error_deg %g", out.error_deg);
  DPC_FUZZ_CHECK(out.nullspace_active_fraction <= 1.0, "out-of-range", "accepted a fraction %g",
                 out.nullspace_active_fraction);
  DPC_FUZZ_CHECK(!out.controller_id.empty(), "contract", "accepted a status without a controller id");
  DPC_FUZZ_CHECK(Printable(out.controller_id) && Printable(out.law) && Printable(out.condition) &&
                     Printable(out.last_rejection),
                 "control-char", "a control character reached the text");
  return 0;
}
