// The raw DDS failover reference (see raw_ownership.h): EXCLUSIVE-ownership writers and reader
// on a topic of their own, built with Fast DDS directly from the bench's QoS profiles.

#include "raw_ownership.h"

#include <signal.h>
#include <sys/prctl.h>
#include <time.h>

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <utility>

#include "dpc/bench/clock.h"
#include "dpc/bus/bus_participant.h"

namespace dpc::bus_benchmark {
namespace {

namespace fdds = eprosima::fastdds::dds;
using testing::Eventually;
using namespace std::chrono_literals;

constexpr char kOwnedTopic[] = "dpc_bench_owned";

class OwnedReader : public fdds::DataReaderListener {
 public:
  void on_data_available(fdds::DataReader* reader) override {
    msg::StokesSample sample;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::lock_guard<std::mutex> lock(mutex);
      arrivals.emplace_back(WallClockNs(), static_cast<int>(sample.optical_power_w()));
    }
  }
  std::mutex mutex;
  std::vector<std::pair<int64_t, int>> arrivals;  ///< (wall ns, writer strength)
  size_t CountFrom(int strength) {
    std::lock_guard<std::mutex> lock(mutex);
    size_t n = 0;
    for (const auto& a : arrivals) n += a.second == strength;
    return n;
  }
};

}  // namespace

int RunRawOwner(int domain, int strength, double rate_hz) {
  bus::BusParticipant participant({domain, "dpc-bench-owner", {}});
  fdds::TypeSupport type(new msg::StokesSamplePubSubType());
  type.register_type(participant.raw());
  fdds::Topic* topic = participant.raw()->create_topic(kOwnedTopic, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  fdds::Publisher* publisher = participant.raw()->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  fdds::DataWriterQos qos;
  publisher->get_datawriter_qos_from_profile("dpc_stokes_sample.writer", qos);
  qos.ownership().kind = fdds::EXCLUSIVE_OWNERSHIP_QOS;
  qos.ownership_strength().value = static_cast<uint32_t>(strength);
  fdds::DataWriter* writer = publisher->create_datawriter(topic, qos);
  if (writer == nullptr) return 1;
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  msg::StokesSample sample;
  sample.bench_id("owned");
  sample.s_in({1, 0, 0});
  sample.s_out({1, 0, 0});
  sample.optical_power_known(true);
  sample.optical_power_w(strength);
  const int64_t period_ns = static_cast<int64_t>(1e9 / rate_hz);
  int64_t next_ns = MonotonicNs();
  const timespec poll{0, 0};
  for (uint64_t k = 1;; ++k) {
    next_ns += period_ns;
    SleepUntilMonotonicNs(next_ns);
    sample.sequence_number(k);
    sample.publish_time_ns(WallClockNs());
    writer->write(&sample);
    // The stop signal is polled, not waited for: the writer must keep its period.
    if ((k & 63) == 0 && sigtimedwait(&set, nullptr, &poll) > 0) break;
  }
  publisher->delete_datawriter(writer);
  return 0;
}

std::vector<double> RawFailover(const BusBenchmarkHarness& harness, int repetitions) {
  std::vector<double> gaps_ms;
  const std::string domain = std::to_string(harness.domain);
  for (int r = 0; r < repetitions; ++r) {
    bus::BusParticipant participant({harness.domain, "dpc-bench-owned-reader", {}});
    fdds::TypeSupport type(new msg::StokesSamplePubSubType());
    type.register_type(participant.raw());
    fdds::Topic* topic = participant.raw()->create_topic(kOwnedTopic, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    fdds::Subscriber* subscriber = participant.raw()->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    fdds::DataReaderQos qos;
    subscriber->get_datareader_qos_from_profile("dpc_stokes_sample.reader", qos);
    qos.ownership().kind = fdds::EXCLUSIVE_OWNERSHIP_QOS;
    OwnedReader listener;
    fdds::DataReader* reader = subscriber->create_datareader(topic, qos, &listener);
    {
      // Both writers end with this block, before the reader they write to.
      const auto strong = harness.StartSelf({"--raw-owner", "10", "--domain", domain}, "owner_strong");
      const auto weak = harness.StartSelf({"--raw-owner", "1", "--domain", domain}, "owner_weak");
      if (Eventually([&] { return listener.CountFrom(10) > 5000; }, 30s)) {
        strong->Signal(SIGKILL);
        Eventually([&] { return listener.CountFrom(1) > 1000; }, 10s);
        std::lock_guard<std::mutex> lock(listener.mutex);
        int64_t last_strong_ns = 0, first_weak_ns = 0;
        for (const auto& [t, s] : listener.arrivals) {
          if (s == 10) last_strong_ns = t;
        }
        for (const auto& [t, s] : listener.arrivals) {
          if (s == 1 && t > last_strong_ns) {
            first_weak_ns = t;
            break;
          }
        }
        if (first_weak_ns > 0) gaps_ms.push_back(static_cast<double>(first_weak_ns - last_strong_ns) * 1e-6);
      }
    }
    reader->set_listener(nullptr);
    subscriber->delete_datareader(reader);
  }
  return gaps_ms;
}

}  // namespace dpc::bus_benchmark
