#pragma once
// What the fuzz targets share: the report of a broken promise and the checks on what a check
// accepts (the message targets read their input with fuzz_wire.h).
//
// A broken promise is a finding. DPC_FUZZ_CHECK(condition, key, format, ...) reports it on
// stderr as "dpc-fuzz: [key] file:line: message" and traps (__builtin_trap: libFuzzer reports a
// crash and writes the input). The keys:
//
//   cdr-exception   the generated PubSubType::deserialize let a Fast CDR exception out (it
//                   catches only NotEnoughMemoryException); on the bus that exception escapes
//                   into Fast DDS's receive thread and std::terminate ends the service
//                   (tests/fuzz/crashes/README.md)
//   idl-bound       an accepted message or device exceeds a bound of idl/dpc/bench.idl
//   non-finite      an accepted value is NaN or infinite
//   out-of-range    an accepted value is outside what the check promises (unit length, sizes,
//                   enumerations, ramp length)
//   motion-overflow an accepted state's motion φ(t) is not finite inside its own ramp
//   contract        the output is not what the check documents (fields not copied, a reused
//                   output that keeps stale values, fields not read on a refusal)
//   build           a validated configuration that the builders refuse
//   exception       an exception of a type the function does not document
//
// DPC_FUZZ_KNOWN="key,key" turns those keys from traps into counts, so that fuzzing goes on
// past a finding already reported (the first occurrence of each is still printed, and the
// counts at exit: "dpc-fuzz: known finding [key] tolerated N times"). Unset: every key traps.

#include <array>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "dpc/optics/stokes.h"

namespace dpc::fuzz {

class Findings {
 public:
  static Findings& Get() {
    static Findings findings;
    return findings;
  }

  /// Reports a broken promise; traps unless `key` is listed in DPC_FUZZ_KNOWN.
  [[gnu::format(printf, 5, 6)]] void Fail(const char* key, const char* file, int line,
                                          const char* format, ...) {
    Entry& entry = counts_[key];
    if (entry.count++ == 0 || !known_.count(key)) {
      std::fprintf(stderr, "dpc-fuzz: [%s] %s:%d: ", key, file, line);
      va_list args;
      va_start(args, format);
      std::vfprintf(stderr, format, args);
      va_end(args);
      std::fputc('\n', stderr);
    }
    if (!known_.count(key)) {
      std::fflush(stderr);
      __builtin_trap();
    }
  }

  ~Findings() {
    for (const auto& [key, entry] : counts_) {
      std::fprintf(stderr, "dpc-fuzz: known finding [%s] tolerated %llu times\n", key.c_str(),
                   static_cast<unsigned long long>(entry.count));
    }
  }

 private:
  Findings() {
    const char* known = std::getenv("DPC_FUZZ_KNOWN");
    std::string list = known ? known : "";
    size_t start = 0;
    while (start <= list.size()) {
      size_t end = list.find(',', start);
      if (end == std::string::npos) end = list.size();
      if (end > start) known_[list.substr(start, end - start)] = true;
      start = end + 1;
    }
  }
  struct Entry {
    uint64_t count = 0;
  };
  std::map<std::string, bool> known_;
  std::map<std::string, Entry> counts_;
};

#define DPC_FUZZ_CHECK(condition, key, ...)                                          \
  do {                                                                               \
    if (!(condition)) ::dpc::fuzz::Findings::Get().Fail(key, __FILE__, __LINE__, __VA_ARGS__); \
  } while (false)

inline bool AllFinite(const std::vector<double>& values) {
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

template <typename Vector>
bool AllFiniteVector(const Vector& values) {
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) return false;
  }
  return true;
}

/// |s| within `tolerance` of 1, every component finite (computed as the checks compute it).
inline bool IsUnit(double x, double y, double z, double tolerance) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return false;
  return std::abs(std::sqrt(x * x + y * y + z * z) - 1.0) <= tolerance;
}

}  // namespace dpc::fuzz
