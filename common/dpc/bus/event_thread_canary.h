#pragma once
// A timer on a participant's Fast DDS event thread, so that a process can tell when that thread
// is stuck for good.
//
// Fast DDS 2.9 with DDS Security deadlocks a participant when a peer's dispose (it left) and
// another peer's lease expiry (it vanished) are processed at the same moment: the receive thread
// removing the first holds SecurityManager's lock while it waits for the event thread to be idle
// (~TimedEvent), and the event thread removing the second waits for that lock. Seen with thread
// stacks on a secured bench: a driver whose controllers left that way never noticed either one
// leaving, never discovered anyone again, and hung when asked to stop (ARCHITECTURE.md, where it
// describes the loop guard). Samples keep flowing through such a participant, so nothing else
// shows it.
//
// The canary is a TimedEvent on the participant's event thread (DomainParticipant::
// get_resource_event) that stamps the time every kPeriodNs. While its participant lives it is
// listed process-wide; OldestEventThreadTickNs gives the stamp of the one that ticked longest
// ago, which the loop guard judges (cli::LoopGuard): a service whose participant has stopped
// ticking exits for its supervisor to restart it, since a participant so stuck cannot even be
// deleted.

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>

namespace eprosima::fastdds::dds {
class DomainParticipant;
}
namespace eprosima::fastrtps::rtps {
class TimedEvent;
}

namespace dpc::bus {

class EventThreadCanary {
 public:
  static constexpr int64_t kPeriodNs = 100'000'000;

  /// Starts ticking on `participant`'s event thread (it must be enabled and outlive the canary).
  explicit EventThreadCanary(eprosima::fastdds::dds::DomainParticipant* participant);
  /// Stops the timer: waits for the event thread to be idle (forever if it is stuck, which the
  /// loop guard ends first).
  ~EventThreadCanary();
  EventThreadCanary(const EventThreadCanary&) = delete;
  EventThreadCanary& operator=(const EventThreadCanary&) = delete;

  /// The steady-clock time (ns) of the last tick (of the canary's creation before the first).
  int64_t last_tick_ns() const { return last_tick_ns_.load(std::memory_order_relaxed); }

 private:
  std::atomic<int64_t> last_tick_ns_;
  std::unique_ptr<eprosima::fastrtps::rtps::TimedEvent> event_;
};

/// Of the canaries alive in this process, the oldest last tick (steady-clock ns); none if there
/// is none. Thread-safe; what a loop guard's heartbeat asks.
std::optional<int64_t> OldestEventThreadTickNs();

/// How long a canary may stay silent before its process is judged stuck: a working event thread
/// is late by milliseconds (a handshake's key agreement, a burst of discovery), not seconds.
inline constexpr double kEventThreadStuckS = 3.0;
/// The heartbeat's name in the loop guard's message.
inline constexpr char kEventThreadWhat[] =
    "the event thread of its DDS participant (Fast DDS 2.9 deadlocks it when a peer leaves as another's lease "
    "expires; such a participant never discovers nor lets go of a peer again, and cannot be deleted)";

}  // namespace dpc::bus
