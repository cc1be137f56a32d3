// The replies a real instrument sends (dpc/instrument/line_link.h): ParseStokesReply (the
// polarimeter's "s1,s2,s3[,…]") and ParseNumberReply (a channel read back) on any bytes. An
// accepted reply gives finite unit vectors (the bench publishes them as they are) or a finite
// number; nothing throws.
#include <cmath>
#include <cstdint>
#include <string>

#include "dpc/instrument/line_link.h"
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const int vectors = 1 + (data[0] & 1);  // S_out alone, or S_in and S_out
  const double min_dop = (data[0] >> 1) / 128.0 + 1e-3;
  const std::string reply(reinterpret_cast<const char*>(data + 1), size - 1);
  dpc::StokesVector s[2];
  if (dpc::instrument::ParseStokesReply(reply, vectors, min_dop, s).empty()) {
    for (int v = 0; v < vectors; ++v) {
      DPC_FUZZ_CHECK(std::isfinite(s[v][0]) && std::isfinite(s[v][1]) && std::isfinite(s[v][2]), "non-finite",
                     "an accepted reply gave a non-finite Stokes vector");
      DPC_FUZZ_CHECK(std::abs(s[v].norm() - 1.0) < 1e-9, "out-of-range", "an accepted reply is not unit (|S| = %g)",
                     s[v].norm());
    }
  }
  double value = 0.0;
  if (dpc::instrument::ParseNumberReply(reply, &value).empty()) {
    DPC_FUZZ_CHECK(std::isfinite(value), "non-finite", "an accepted number is not finite");
  }
  return 0;
}
