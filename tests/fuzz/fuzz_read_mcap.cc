// ReadMcap and ReadMcapSummary (record/mcap.h) on any file: a recording cut short, damaged or
// forged is read up to its damage and reported, never crashes, loops or allocates what it
// claims without bound. The only exception is the documented one (no MCAP magic).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "dpc/record/mcap.h"
#include "fuzz_support.h"

namespace {
// The reader goes through a file: one per fuzzing process, removed when it exits.
struct InputFile {
  std::string path = "/dev/shm/dpc-fuzz-mcap-" + std::to_string(::getpid()) + ".mcap";
  ~InputFile() { std::remove(path.c_str()); }
};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const InputFile input;
  const std::string& path = input.path;
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return 0;
  std::fwrite(data, 1, size, file);
  std::fclose(file);
  uint64_t messages = 0;
  try {
    const dpc::record::McapReadResult result =
        dpc::record::ReadMcap(path, [&](const dpc::record::McapChannel&, const dpc::record::McapMessage& m) {
          ++messages;
          DPC_FUZZ_CHECK(m.data.size() <= size, "contract", "a message larger than the file (%zu bytes)",
                         m.data.size());
        });
    DPC_FUZZ_CHECK(result.messages == messages, "contract", "counted %llu messages, delivered %llu",
                   static_cast<unsigned long long>(result.messages), static_cast<unsigned long long>(messages));
    DPC_FUZZ_CHECK(!result.complete || result.problem.empty(), "contract", "complete with a problem");
  } catch (const std::runtime_error&) {
    // not MCAP (no magic): the documented exception
  }
  (void)dpc::record::ReadMcapSummary(path);
  return 0;
}
