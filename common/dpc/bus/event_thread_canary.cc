#include "dpc/bus/event_thread_canary.h"

#include <algorithm>
#include <mutex>
#include <set>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/rtps/resources/TimedEvent.h>

#include "dpc/bench/clock.h"

namespace dpc::bus {
namespace {

std::mutex& CanariesMutex() {
  static std::mutex mutex;
  return mutex;
}
std::set<const EventThreadCanary*>& Canaries() {
  static std::set<const EventThreadCanary*> canaries;
  return canaries;
}

}  // namespace

EventThreadCanary::EventThreadCanary(eprosima::fastdds::dds::DomainParticipant* participant)
    : last_tick_ns_(MonotonicNs()) {
  event_ = std::make_unique<eprosima::fastrtps::rtps::TimedEvent>(
      participant->get_resource_event(),
      [this] {
        last_tick_ns_.store(MonotonicNs(), std::memory_order_relaxed);
        return true;  // again after kPeriodNs
      },
      static_cast<double>(kPeriodNs) * 1e-6);
  event_->restart_timer();
  std::lock_guard<std::mutex> lock(CanariesMutex());
  Canaries().insert(this);
}

EventThreadCanary::~EventThreadCanary() {
  {
    std::lock_guard<std::mutex> lock(CanariesMutex());
    Canaries().erase(this);
  }
  event_.reset();  // outside the list's lock: this waits for the event thread
}

std::optional<int64_t> OldestEventThreadTickNs() {
  std::lock_guard<std::mutex> lock(CanariesMutex());
  std::optional<int64_t> oldest;
  for (const EventThreadCanary* canary : Canaries()) {
    const int64_t tick_ns = canary->last_tick_ns();
    oldest = oldest ? std::min(*oldest, tick_ns) : tick_ns;
  }
  return oldest;
}

}  // namespace dpc::bus
