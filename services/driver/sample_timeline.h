#pragma once
// What the driver knows of the bench's samples from the polarimeter itself: the newest sample's
// number, and the number, bench time and publish time of the latest kCapacity samples. A
// command names the sample it answers; the driver judges that claim by this record, never by
// the numbers and times the command carries:
//   - a command may answer a recorded sample, or one at most kMaxLead past the newest (its
//     sample may still be on its way to the driver); anything further ahead is refused, so no
//     command can make every controller look "behind" (arbitration) or jump the bookkeeping;
//   - the motion a command starts is placed at its sample's recorded bench time (or, for a
//     sample not recorded, the time extrapolated from the newest at the recorded period),
//     whatever sample_time_ns the command says; a command whose sample_time_ns contradicts the
//     record is refused.
// A sample numbered at or before the newest is a new bench run (DDS drops one writer's
// out-of-order samples): the record starts afresh. The newest sample again, at its time, is no
// restart (a lockstep bench re-publishes it while it waits for its answer).
//
// O(1) per sample and per query, fixed memory, no allocation.

#include <array>
#include <cstdint>
#include <optional>
#include <string>

namespace dpc::services {

class SampleTimeline {
 public:
  static constexpr uint64_t kCapacity = 1024;
  /// How far past the newest recorded sample a command may answer (its sample still in flight).
  static constexpr uint64_t kMaxLead = 64;

  struct Sample {
    uint64_t sequence = 0;     ///< 0: empty slot
    int64_t time_ns = 0;       ///< bench time (sample_time_ns)
    int64_t publish_time_ns = 0;
  };

  /// A sample published by the bench (sequence ≥ 1). Returns true if it shows that the bench
  /// restarted (the record was cleared and starts with this sample).
  bool OnSample(uint64_t sequence, int64_t time_ns, int64_t publish_time_ns);

  /// The newest sample's number (0: none yet).
  uint64_t newest() const { return newest_.sequence; }

  /// The record of `sequence`, if it is one of the latest kCapacity samples seen.
  std::optional<Sample> Find(uint64_t sequence) const;

  /// Empty if a command may answer `sequence`: one the bench published (recorded), or at most
  /// kMaxLead past the newest; else why not.
  std::string CheckSequence(uint64_t sequence) const;
  /// Empty if a command may answer `sequence` with `claimed_time_ns`: CheckSequence, and the
  /// claimed time is the recorded one; else why not.
  std::string CheckAnswer(uint64_t sequence, int64_t claimed_time_ns) const;

  /// The bench time of `sequence` (one that passed CheckAnswer): recorded, or extrapolated from
  /// the newest sample at the period of the latest two (the bench's sample times are nominal,
  /// k · period); saturated, never overflowing.
  int64_t TimeOfNs(uint64_t sequence) const;

 private:
  void Clear();

  std::array<Sample, kCapacity> ring_{};
  Sample newest_;
  double period_ns_ = 0.0;   ///< between the latest two samples, per sample
};

}  // namespace dpc::services
