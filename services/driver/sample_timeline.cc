#include "sample_timeline.h"

#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace dpc::services {

void SampleTimeline::Clear() {
  ring_.fill(Sample{});
  newest_ = Sample{};
  period_ns_ = 0.0;
}

bool SampleTimeline::OnSample(uint64_t sequence, int64_t time_ns, int64_t publish_time_ns) {
  if (sequence == 0) return false;
  bool restarted = false;
  if (newest_.sequence != 0 && sequence <= newest_.sequence) {
    // The newest sample again: a lockstep bench re-publishes it while it waits for its answer.
    if (sequence == newest_.sequence && time_ns == newest_.time_ns) return false;
    // An earlier number (DDS drops a writer's out-of-order samples): a new bench run.
    Clear();
    restarted = true;
  }
  const Sample sample{sequence, time_ns, publish_time_ns};
  ring_[sequence % kCapacity] = sample;
  if (newest_.sequence != 0) {
    // The bench's sample times are nominal (k · period): two samples give the period exactly.
    period_ns_ = (static_cast<double>(time_ns) - static_cast<double>(newest_.time_ns)) /
                 static_cast<double>(sequence - newest_.sequence);
  }
  newest_ = sample;
  return restarted;
}

std::optional<SampleTimeline::Sample> SampleTimeline::Find(uint64_t sequence) const {
  if (sequence == 0) return std::nullopt;
  const Sample& slot = ring_[sequence % kCapacity];
  if (slot.sequence != sequence) return std::nullopt;
  return slot;
}

std::string SampleTimeline::CheckAnswer(uint64_t sequence, int64_t claimed_time_ns) const {
  if (const std::optional<Sample> known = Find(sequence); known && known->time_ns != claimed_time_ns) {
    return fmt::format("sample_time_ns {} is not the time of sample {} ({})", claimed_time_ns, sequence,
                       known->time_ns);
  }
  return CheckSequence(sequence);
}

std::string SampleTimeline::CheckSequence(uint64_t sequence) const {
  if (sequence == 0) return "answers_sample 0: answers no sample";
  if (Find(sequence)) return {};
  if (sequence > newest_.sequence && sequence - newest_.sequence > kMaxLead) {
    return newest_.sequence == 0
               ? fmt::format("answers sample {}, but no sample of the bench has arrived yet", sequence)
               : fmt::format("answers sample {}, but the bench's newest sample is {}", sequence,
                             newest_.sequence);
  }
  return {};
}

int64_t SampleTimeline::TimeOfNs(uint64_t sequence) const {
  if (const std::optional<Sample> known = Find(sequence)) return known->time_ns;
  if (newest_.sequence == 0) return 0;
  // Not recorded (lost, or still on its way): at the bench's period.
  const double offset_samples = sequence >= newest_.sequence
                                    ? static_cast<double>(sequence - newest_.sequence)
                                    : -static_cast<double>(newest_.sequence - sequence);
  const double time_ns = static_cast<double>(newest_.time_ns) + offset_samples * period_ns_;
  constexpr double kLimit = 9.2e18;
  if (!(time_ns < kLimit)) return std::numeric_limits<int64_t>::max();
  if (!(time_ns > -kLimit)) return std::numeric_limits<int64_t>::min();
  return static_cast<int64_t>(time_ns);
}

}  // namespace dpc::services
