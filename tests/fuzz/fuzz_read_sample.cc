// ReadSample (bus/message_conversion.h) on any StokesSample payload a peer can send.
#include <cmath>
#include <cstdint>

#include "dpc/bus/message_conversion.h"
#include "fuzz_wire.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dpc;
  msg::StokesSample message;
  if (!fuzz::FromWire(data, size, &message)) return 0;
  BenchSample out;
  if (!bus::ReadSample(message, &out).empty()) return 0;

  // Accepted: a positive sequence, finite unit S_in and S_out, a finite power >= 0 if known.
  DPC_FUZZ_CHECK(out.sequence != 0, "out-of-range", "accepted sequence_number 0");
  DPC_FUZZ_CHECK(fuzz::AllFiniteVector(out.s_in) && fuzz::AllFiniteVector(out.s_out), "non-finite",
                 "accepted a non-finite Stokes vector");
  DPC_FUZZ_CHECK(fuzz::IsUnit(out.s_in.x(), out.s_in.y(), out.s_in.z(), bus::kUnitStokesTolerance),
                 "out-of-range", "accepted s_in |S| = %.17g", out.s_in.norm());
  DPC_FUZZ_CHECK(fuzz::IsUnit(out.s_out.x(), out.s_out.y(), out.s_out.z(), bus::kUnitStokesTolerance),
                 "out-of-range", "accepted s_out |S| = %.17g", out.s_out.norm());
  DPC_FUZZ_CHECK(out.optical_power_w.has_value() == message.optical_power_known(), "contract",
                 "optical power known %d, read %d", message.optical_power_known(),
                 out.optical_power_w.has_value());
  if (out.optical_power_w) {
    DPC_FUZZ_CHECK(std::isfinite(*out.optical_power_w), "non-finite", "accepted power %g",
                   *out.optical_power_w);
    DPC_FUZZ_CHECK(*out.optical_power_w >= 0.0, "out-of-range", "accepted power %g",
                   *out.optical_power_w);
  }
  DPC_FUZZ_CHECK(out.sequence == message.sequence_number() && out.time_ns == message.sample_time_ns() &&
                     out.publish_time_ns == message.publish_time_ns() &&
                     out.lockstep == message.lockstep() && out.s_in.x() == message.s_in()[0] &&
                     out.s_out.z() == message.s_out()[2],
                 "contract", "accepted sample not copied field for field");
  return 0;
}
