// BusParticipant: profiles resolution, participants and typed readers and writers on the
// loopback-only profile. Every participant here uses deploy/fastdds/loopback.xml and a DDS
// domain of 64–70 (this file's share of the tests' range 60–79), so nothing leaves the host and
// no other test's traffic meets these.
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/participant_maker.h"

#include <fastdds/rtps/resources/TimedEvent.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <ctime>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>
#include <thread>
#include <algorithm>

#include "support/process.h"

namespace dpc::bus {
namespace {

using namespace std::chrono_literals;
using dpc::testing::Eventually;
using dpc::testing::Slurp;

const std::string kLoopbackProfiles = std::string(DPC_SOURCE_DIR) + "/deploy/fastdds/loopback.xml";
constexpr int kExchangeDomain = 64;
constexpr int kOtherBenchDomain = 65;
constexpr int kParticipantDomain = 66;
constexpr int kPartitionDomain = 67;
constexpr int kInstancesDomain = 68;
constexpr int kDeadlineDomain = 70;
constexpr auto kDiscoveryTimeout = 10s;

msg::StokesSample Sample(const std::string& bench_id, uint64_t sequence) {
  msg::StokesSample m;
  m.bench_id(bench_id);
  m.sequence_number(sequence);
  m.sample_time_ns(static_cast<int64_t>(sequence) * 100'000);
  m.s_in({1.0, 0.0, 0.0});
  m.s_out({0.0, 0.6, 0.8});
  return m;
}

/// What a reader's callback saw, from Fast DDS's listener thread.
class Received {
 public:
  void Add(const msg::StokesSample& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    samples_.push_back(m);
  }
  std::vector<msg::StokesSample> samples() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return samples_;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<msg::StokesSample> samples_;
};

// Points FASTRTPS_DEFAULT_PROFILES_FILE at the loopback profile for each test and restores the
// caller's environment afterwards.
class BusParticipantTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const char* value = std::getenv(kProfilesEnvironmentVariable)) saved_ = value;
    setenv(kProfilesEnvironmentVariable, kLoopbackProfiles.c_str(), 1);
  }
  void TearDown() override {
    if (saved_) {
      setenv(kProfilesEnvironmentVariable, saved_->c_str(), 1);
    } else {
      unsetenv(kProfilesEnvironmentVariable);
    }
  }

  static BusOptions Options(int domain_id, const std::string& name) {
    BusOptions options;
    options.domain_id = domain_id;
    options.participant_name = name;
    return options;
  }

  std::optional<std::string> saved_;
};

TEST_F(BusParticipantTest, ResolveProfilesFileReturnsTheFileTheVariableNames) {
  EXPECT_EQ(ResolveProfilesFile(), kLoopbackProfiles);
}

TEST_F(BusParticipantTest, ResolveProfilesFileRefusesAMissingFileAndNamesIt) {
  const std::string missing = (std::filesystem::temp_directory_path() /
                               ("dpc_bus_test_missing_" + std::to_string(::getpid()) + ".xml"))
                                  .string();
  setenv(kProfilesEnvironmentVariable, missing.c_str(), 1);
  try {
    ResolveProfilesFile();
    FAIL() << "a missing profiles file resolved";
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(kProfilesEnvironmentVariable), std::string::npos) << e.what();
  }
}

TEST_F(BusParticipantTest, ResolveProfilesFileWithoutTheVariableFindsTheShippedLoopbackProfile) {
  for (const char* value : {static_cast<const char*>(nullptr), ""}) {  // unset, or set empty
    if (value == nullptr) {
      unsetenv(kProfilesEnvironmentVariable);
    } else {
      setenv(kProfilesEnvironmentVariable, value, 1);
    }
    const std::string file = ResolveProfilesFile();
    // The copy next to the binaries or the source tree's: the same shipped file either way.
    EXPECT_EQ(std::filesystem::path(file).filename(), "loopback.xml") << file;
    EXPECT_EQ(Slurp(file), Slurp(kLoopbackProfiles)) << file;
  }
}

TEST_F(BusParticipantTest, AParticipantOnTheLoopbackProfileUsesNoBuiltinTransport) {
  BusParticipant participant(Options(kParticipantDomain, "dpc_bus_test"));
  EXPECT_EQ(participant.profiles_file(), kLoopbackProfiles);
  ASSERT_NE(participant.raw(), nullptr);
  EXPECT_EQ(participant.raw()->get_domain_id(), kParticipantDomain);
  const auto qos = participant.raw()->get_qos();
  EXPECT_EQ(std::string(qos.name().c_str()), "dpc_bus_test");
  // Only the profile's UDPv4 transport on 127.0.0.1: nothing binds another interface.
  EXPECT_FALSE(qos.transport().use_builtin_transports);
  EXPECT_EQ(qos.transport().user_transports.size(), 1u);
}

TEST_F(BusParticipantTest, AnAskedUdpReceiveBufferRaisesThisParticipantsOnlyAndKeepsTheWhitelist) {
  namespace rtps = eprosima::fastdds::rtps;
  const auto udp_of = [](const BusParticipant& participant) {
    const auto qos = participant.raw()->get_qos();
    EXPECT_EQ(qos.transport().user_transports.size(), 1u);
    return std::dynamic_pointer_cast<rtps::UDPv4TransportDescriptor>(qos.transport().user_transports.at(0));
  };
  BusOptions options = Options(kParticipantDomain, "dpc_bus_test_recorder");
  options.udp_receive_buffer_bytes = 8u << 20;
  BusParticipant recorder(options);
  const auto raised = udp_of(recorder);
  ASSERT_NE(raised, nullptr);
  EXPECT_EQ(raised->receiveBufferSize, 8u << 20);
  EXPECT_EQ(raised->interfaceWhiteList, std::vector<std::string>{"127.0.0.1"});
  // The profile's descriptor is shared: a participant made after it keeps the profile's size.
  BusParticipant service(Options(kParticipantDomain, "dpc_bus_test_service"));
  const auto kept = udp_of(service);
  ASSERT_NE(kept, nullptr);
  EXPECT_EQ(kept->receiveBufferSize, 0u);
}

TEST_F(BusParticipantTest, AReloadNamesItselfToTheLoopGuardWhileItRunsAndGivesThePhaseBack) {
  ParticipantMaker maker(Options(kParticipantDomain, "dpc_bus_test_reload"), {}, [](bool, const std::string&) {});
  const char* phase = "its ticks";
  maker.SetPhaseReport([&phase](const char* now) { return std::exchange(phase, now); });
  std::unique_ptr<BusParticipant> participant = maker.Make();
  const BusParticipant* before = participant.get();
  std::vector<std::string> seen;
  EXPECT_TRUE(maker.Reload(
      &participant, [&] { seen.emplace_back(phase); }, [&] { seen.emplace_back(phase); }, "SIGHUP"));
  EXPECT_NE(participant.get(), before) << "an open reload moves the endpoints at once";
  EXPECT_EQ(seen, (std::vector<std::string>{ParticipantMaker::kReloadPhase, ParticipantMaker::kReloadPhase}));
  EXPECT_STREQ(phase, "its ticks");
  // A loop with no guard (the report is empty) reloads the same way.
  ParticipantMaker unguarded(Options(kParticipantDomain, "dpc_bus_test_reload"), {}, [](bool, const std::string&) {});
  EXPECT_TRUE(unguarded.Reload(&participant, [] {}, [] {}, "SIGHUP"));
}

TEST(UdpReceiveBufferNoteTest, SaysWhatTheKernelGrantsAndHowToRaiseIt) {
  EXPECT_EQ(UdpReceiveBufferNote(4u << 20, 8u << 20), "UDP receive buffer: 4.0 MiB");
  EXPECT_EQ(UdpReceiveBufferNote(4u << 20, 4u << 20), "UDP receive buffer: 4.0 MiB");
  const std::string capped = UdpReceiveBufferNote(4u << 20, 212992);
  EXPECT_NE(capped.find("4.0 MiB asked, but the kernel grants 0.2 MiB (net.core.rmem_max)"), std::string::npos)
      << capped;
  EXPECT_NE(capped.find("sysctl -w net.core.rmem_max=4194304"), std::string::npos) << capped;
  EXPECT_NE(UdpReceiveBufferNote(1u << 20, 0).find("could not be read"), std::string::npos);
  EXPECT_EQ(GrantedUdpReceiveBufferBytes(4u << 20, 212992), 212992u);
  EXPECT_EQ(GrantedUdpReceiveBufferBytes(4u << 20, 8u << 20), 4u << 20);
  EXPECT_EQ(GrantedUdpReceiveBufferBytes(4u << 20, 0), 4u << 20);
}

TEST_F(BusParticipantTest, AWriterAndAReaderInTwoParticipantsExchangeASample) {
  BusParticipant publishing(Options(kExchangeDomain, "dpc_bus_test_writer"));
  BusParticipant subscribing(Options(kExchangeDomain, "dpc_bus_test_reader"));
  Received received;
  auto reader = subscribing.MakeReader<msg::StokesSample>(
      "bench1", [&](const msg::StokesSample& m, const eprosima::fastdds::dds::SampleInfo&) { received.Add(m); });
  auto writer = publishing.MakeWriter<msg::StokesSample>("bench1");
  ASSERT_TRUE(Eventually([&] { return writer->matched_readers() == 1 && reader->counters().matched_writers == 1; },
                         kDiscoveryTimeout));
  // Best effort: a sample may be lost, so keep writing until one arrives.
  const msg::StokesSample sample = Sample("bench1", 7);
  ASSERT_TRUE(Eventually([&] { return writer->Write(sample) && reader->counters().samples >= 1; }, kDiscoveryTimeout));
  const std::vector<msg::StokesSample> samples = received.samples();
  ASSERT_FALSE(samples.empty());
  EXPECT_EQ(samples[0].bench_id().to_string(), "bench1");
  EXPECT_EQ(samples[0].sequence_number(), 7u);
  EXPECT_EQ(samples[0].sample_time_ns(), 700'000);
  EXPECT_EQ(samples[0].s_out(), sample.s_out());
  EXPECT_EQ(reader->counters().other_benches.load(), 0u);
}

TEST_F(BusParticipantTest, OnlyAReaderThatWatchesTheDeadlineRequestsItAndCountsItsMisses) {
  BusParticipant publishing(Options(kDeadlineDomain, "dpc_bus_test_writer"));
  BusParticipant subscribing(Options(kDeadlineDomain, "dpc_bus_test_reader"));
  auto ignore = [](const msg::StokesSample&, const eprosima::fastdds::dds::SampleInfo&) {};
  auto quiet = subscribing.MakeReader<msg::StokesSample>("bench1", ignore);
  auto watching = subscribing.MakeReader<msg::StokesSample>("bench1", ignore, DeadlineWatch::kOn);
  auto writer = publishing.MakeWriter<msg::StokesSample>("bench1");
  // Both match the writer, which offers the profile's 20 ms.
  ASSERT_TRUE(Eventually([&] {
    return writer->matched_readers() == 2 && quiet->counters().matched_writers == 1 &&
           watching->counters().matched_writers == 1;
  }, kDiscoveryTimeout));
  eprosima::fastdds::dds::DataReaderQos qos;
  ASSERT_EQ(quiet->raw()->get_qos(qos), ReturnCode_t::RETCODE_OK);
  EXPECT_EQ(qos.deadline().period, eprosima::fastrtps::c_TimeInfinite);
  ASSERT_EQ(watching->raw()->get_qos(qos), ReturnCode_t::RETCODE_OK);
  EXPECT_EQ(qos.deadline().period, eprosima::fastrtps::Duration_t(0, 20'000'000));
  // One sample, then silence for many periods: only the watching reader misses deadlines.
  ASSERT_TRUE(Eventually([&] {
    return writer->Write(Sample("bench1", 1)) && quiet->counters().samples >= 1 && watching->counters().samples >= 1;
  }, kDiscoveryTimeout));
  EXPECT_TRUE(Eventually([&] { return watching->counters().deadline_misses >= 2; }, 5s));
  EXPECT_EQ(quiet->counters().deadline_misses.load(), 0u);
}

TEST_F(BusParticipantTest, PeerEventsNameAParticipantWhenItArrivesAndWhenItLeaves) {
  std::mutex mutex;
  std::vector<std::string> events;
  BusParticipant watcher(Options(kExchangeDomain, "dpc_bus_test_watcher"), [&](const PeerEvent& event) {
    std::lock_guard<std::mutex> lock(mutex);
    events.push_back(Describe(event));
  });
  auto seen = [&](const std::string& text) {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& e : events) {
      if (e.find(text) != std::string::npos) return true;
    }
    return false;
  };
  {
    BusParticipant visitor(Options(kExchangeDomain, "dpc_bus_test_visitor"));
    EXPECT_TRUE(Eventually([&] { return seen("participant discovered: "); }, kDiscoveryTimeout));
    EXPECT_TRUE(seen("(dpc_bus_test_visitor)"));
  }
  // Deleted: it says goodbye (no lease expiry to wait for).
  EXPECT_TRUE(Eventually([&] { return seen("participant gone: "); }, kDiscoveryTimeout));
  // Two events of the visitor's (other tests' participants may share the domain under ctest -j).
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_EQ(std::count_if(events.begin(), events.end(),
                          [](const std::string& e) { return e.find("(dpc_bus_test_visitor)") != std::string::npos; }),
            2)
      << ::testing::PrintToString(events);
}

// HasLeft: what lets a service's SourceBinding take a new source at once when its bound one left.
TEST_F(BusParticipantTest, AParticipantThatLeftIsKnownToHaveLeft) {
  BusParticipant watcher(Options(kExchangeDomain, "dpc_bus_test_left_watcher"));
  SourceId visitor_id{};
  {
    BusParticipant visitor(Options(kExchangeDomain, "dpc_bus_test_left_visitor"));
    visitor_id = SourceOf(visitor.raw()->guid().guidPrefix);
    EXPECT_EQ(SourceOf(PrefixOf(visitor_id)), visitor_id);
    EXPECT_FALSE(watcher.HasLeft(visitor_id)) << "never seen";
    ASSERT_TRUE(Eventually(
        [&] {
          for (const auto& p : watcher.raw()->get_participant_names()) {
            if (p == "dpc_bus_test_left_visitor") return true;
          }
          return false;
        },
        kDiscoveryTimeout));
    EXPECT_FALSE(watcher.HasLeft(visitor_id)) << "discovered, still there";
  }
  // Deleted: it says goodbye.
  EXPECT_TRUE(Eventually([&] { return watcher.HasLeft(visitor_id); }, kDiscoveryTimeout));
  EXPECT_FALSE(watcher.HasLeft(SourceOf(watcher.raw()->guid().guidPrefix)));
}

TEST(PrintableNameTest, APeersChosenNameCannotBreakALogLine) {
  EXPECT_EQ(PrintableName("dpc-driver/bench1"), "dpc-driver/bench1");
  EXPECT_EQ(PrintableName("evil\n12:00:00.000 [driver bench1] info: obeying x\x1b[2J"),
            "evil?12:00:00.000 [driver bench1] info: obeying x?[2J");
  EXPECT_EQ(PrintableName(std::string(100, 'a')), std::string(64, 'a') + "…");
}

TEST_F(BusParticipantTest, AReaderCountsAndSkipsSamplesOfAnotherBench) {
  BusParticipant publishing(Options(kOtherBenchDomain, "dpc_bus_test_writer"));
  BusParticipant subscribing(Options(kOtherBenchDomain, "dpc_bus_test_reader"));
  Received received;
  auto reader = subscribing.MakeReader<msg::StokesSample>(
      "bench1", [&](const msg::StokesSample& m, const eprosima::fastdds::dds::SampleInfo&) { received.Add(m); });
  auto writer = publishing.MakeWriter<msg::StokesSample>("");  // every bench's partition
  ASSERT_TRUE(Eventually([&] { return writer->matched_readers() == 1 && reader->counters().matched_writers == 1; },
                         kDiscoveryTimeout));
  const msg::StokesSample other = Sample("bench2", 100);
  const msg::StokesSample own = Sample("bench1", 1);
  ASSERT_TRUE(Eventually(
      [&] {
        writer->Write(other);
        writer->Write(own);
        return reader->counters().other_benches >= 1 && reader->counters().samples >= 1;
      },
      kDiscoveryTimeout));
  const std::vector<msg::StokesSample> samples = received.samples();
  ASSERT_FALSE(samples.empty());
  for (const msg::StokesSample& m : samples) {
    EXPECT_EQ(m.bench_id().to_string(), "bench1");
    EXPECT_EQ(m.sequence_number(), 1u);
  }
}

TEST_F(BusParticipantTest, ADomainOutOfTheDdsRangeIsRefusedBeforeAnyParticipant) {
  for (int domain : {233, -1}) {
    try {
      BusParticipant participant(Options(domain, "dpc_bus_test"));
      FAIL() << "domain " << domain << " accepted";
    } catch (const BusError& e) {
      EXPECT_NE(std::string(e.what()).find("domain " + std::to_string(domain)), std::string::npos) << e.what();
    }
  }
}

// The canary ticks on the participant's event thread, and stops ticking while that thread is
// held (here by an event of the test's own that waits: what Fast DDS 2.9's deadlock does to it).
TEST_F(BusParticipantTest, TheEventThreadCanaryTicksAndStopsWhileTheEventThreadIsHeld) {
  EXPECT_FALSE(OldestEventThreadTickNs().has_value()) << "no participant, no canary";
  // Whether the canary ticks after `after_ns` within 5 s (a loaded machine delays the thread).
  const auto ticks_after = [](int64_t after_ns) {
    for (int i = 0; i < 500; ++i) {
      if (*OldestEventThreadTickNs() > after_ns) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
  };
  {
    BusParticipant participant(Options(kParticipantDomain, "dpc_bus_test"));
    ASSERT_TRUE(OldestEventThreadTickNs().has_value());
    EXPECT_TRUE(ticks_after(*OldestEventThreadTickNs())) << "it ticks";
    EXPECT_TRUE(ticks_after(*OldestEventThreadTickNs())) << "again";

    std::mutex mutex;
    std::condition_variable changed;
    bool holding = false, release = false;
    eprosima::fastrtps::rtps::TimedEvent hold(
        participant.raw()->get_resource_event(),
        [&] {
          std::unique_lock<std::mutex> lock(mutex);
          holding = true;
          changed.notify_all();
          changed.wait(lock, [&] { return release; });
          return false;
        },
        1.0);
    hold.restart_timer();
    {
      std::unique_lock<std::mutex> lock(mutex);
      ASSERT_TRUE(changed.wait_for(lock, std::chrono::seconds(5), [&] { return holding; }));
    }
    const int64_t held_ns = MonotonicNs();
    std::this_thread::sleep_for(std::chrono::nanoseconds(5 * EventThreadCanary::kPeriodNs));
    EXPECT_LT(*OldestEventThreadTickNs(), held_ns) << "no tick while the event thread is held";
    const int64_t released_ns = MonotonicNs();
    {
      std::lock_guard<std::mutex> lock(mutex);
      release = true;
    }
    changed.notify_all();
    EXPECT_TRUE(ticks_after(released_ns)) << "ticking again once the thread is free";
  }
  EXPECT_FALSE(OldestEventThreadTickNs().has_value()) << "the canary goes with its participant";
}

TEST(PartitionTest, EveryBenchHasItsOwnAndEachControllerOneInside) {
  EXPECT_EQ(BenchPartition("bench1"), "dpc.bench1");
  EXPECT_EQ(BenchPartition(""), "dpc.*");
  EXPECT_EQ(ControllerPartition("bench1", "main"), "dpc.bench1.controller.main");
  EXPECT_EQ(ControllerPartition("bench1", ""), "dpc.bench1.controller.*");
  EXPECT_EQ(PartitionFor<msg::WaveplateCommand>("b", "c"), "dpc.b.controller.c");
  EXPECT_EQ(PartitionFor<msg::WaveplateState>("b", "c"), "dpc.b");
  EXPECT_EQ(ControllerOfPartition("bench1", "dpc.bench1.controller.main"), "main");
  EXPECT_EQ(ControllerOfPartition("bench1", "dpc.bench1.controller.*"), "") << "a pattern names nobody";
  EXPECT_EQ(ControllerOfPartition("bench1", "dpc.bench2.controller.main"), "");
  EXPECT_EQ(ControllerOfPartition("bench1", "dpc.bench1"), "");
  EXPECT_EQ(ControllerOfPartition("bench1", ""), "");
}

TEST_F(BusParticipantTest, AnotherBenchsWriterIsNeverMatchedAndACommandsWriterIsKnownByItsPartition) {
  BusParticipant driver(Options(kPartitionDomain, "dpc_bus_test_driver"));
  BusParticipant controllers(Options(kPartitionDomain, "dpc_bus_test_controllers"));
  std::mutex mutex;
  std::vector<std::string> partitions;
  auto reader = driver.MakeReader<msg::WaveplateCommand>(
      "bench1", [&](const msg::WaveplateCommand&, const eprosima::fastdds::dds::SampleInfo& info) {
        std::lock_guard<std::mutex> lock(mutex);
        partitions.push_back(driver.WriterPartition(info.sample_identity.writer_guid()));
      });
  auto foreign = controllers.MakeWriter<msg::WaveplateCommand>("bench2", "main");
  auto own = controllers.MakeWriter<msg::WaveplateCommand>("bench1", "main");
  ASSERT_TRUE(Eventually([&] { return own->matched_readers() == 1; }, kDiscoveryTimeout));
  msg::WaveplateCommand command;
  command.bench_id("bench1");
  command.controller_id("main");
  ASSERT_TRUE(Eventually(
      [&] {
        foreign->Write(command);
        own->Write(command);
        std::lock_guard<std::mutex> lock(mutex);
        return !partitions.empty();
      },
      kDiscoveryTimeout));
  EXPECT_EQ(foreign->matched_readers(), 0) << "bench2's writer reaches no reader of bench1";
  EXPECT_EQ(reader->counters().matched_writers.load(), 1);
  EXPECT_EQ(reader->counters().other_benches.load(), 0u);
  std::lock_guard<std::mutex> lock(mutex);
  for (const std::string& partition : partitions) EXPECT_EQ(partition, "dpc.bench1.controller.main");
}

TEST_F(BusParticipantTest, ForeignKeysInTheBenchsPartitionDoNotCrowdOutANewController) {
  // A buggy or hostile writer in the bench's partition keys commands by 100 other bench ids
  // (Fast DDS's default max_instances, 10, made a controller started later unheard): the
  // profiles' limits (256 instances) leave room for the bench's own controllers.
  BusParticipant driver(Options(kInstancesDomain, "dpc_bus_test_driver"));
  BusParticipant others(Options(kInstancesDomain, "dpc_bus_test_flood"));
  std::mutex mutex;
  std::vector<std::string> heard;
  auto reader = driver.MakeReader<msg::WaveplateCommand>(
      "bench1", [&](const msg::WaveplateCommand& m, const eprosima::fastdds::dds::SampleInfo&) {
        std::lock_guard<std::mutex> lock(mutex);
        heard.push_back(m.controller_id().to_string());
      });
  auto flood = others.MakeWriter<msg::WaveplateCommand>("bench1", "flood");
  // Matched on both sides: a reader that has not discovered the writer yet drops its samples.
  ASSERT_TRUE(Eventually(
      [&] { return flood->matched_readers() == 1 && reader->counters().matched_writers.load() == 1; },
      kDiscoveryTimeout));
  msg::WaveplateCommand command;
  command.controller_id("flood");
  // Rounds of the 100 keys until the reader has taken 100 of them (best effort: a loaded
  // machine may lose some).
  ASSERT_TRUE(Eventually(
      [&] {
        for (int k = 0; k < 100; ++k) {
          command.bench_id("other" + std::to_string(k));
          flood->Write(command);
        }
        std::this_thread::sleep_for(20ms);
        return reader->counters().other_benches.load() >= 100;
      },
      kDiscoveryTimeout));
  auto late = others.MakeWriter<msg::WaveplateCommand>("bench1", "late");
  ASSERT_TRUE(Eventually([&] { return late->matched_readers() == 1; }, kDiscoveryTimeout));
  command.bench_id("bench1");
  command.controller_id("late");
  EXPECT_TRUE(Eventually(
      [&] {
        late->Write(command);
        std::lock_guard<std::mutex> lock(mutex);
        return std::find(heard.begin(), heard.end(), "late") != heard.end();
      },
      2s))
      << "other benches' keys seen: " << reader->counters().other_benches.load();
}

}  // namespace
}  // namespace dpc::bus

namespace dpc::bus {
namespace {

TEST(SecurityPropertiesTest, NameTheBenchFilesAndTheRevocationListOnceARotationWroteIt) {
  EXPECT_TRUE(SecurityProperties({}).empty());
  const std::filesystem::path dir =
      std::filesystem::path(::testing::TempDir()) / ("dpc_security_properties_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir / "ca");
  std::filesystem::create_directories(dir / "driver");
  auto value = [](const auto& properties, const std::string& name) -> std::optional<std::string> {
    for (const auto& [n, v] : properties) {
      if (n == name) return v;
    }
    return std::nullopt;
  };
  const std::string crl_property = "dds.sec.auth.builtin.PKI-DH.identity_crl";
  // (Only their presence matters here: Fast DDS reads them.)
  for (const char* file : {"ca/ca.cert.pem", "governance.p7s", "driver/cert.pem", "driver/key.pem"}) {
    std::ofstream(dir / file) << "-\n";
  }
  try {
    SecurityProperties({dir.string(), "driver"});
    ADD_FAILURE() << "a missing permissions file was not noticed";
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("permissions.p7s is missing"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "driver" / "permissions.p7s") << "-\n";
  const auto before = SecurityProperties({dir.string(), "driver"});
  EXPECT_EQ(value(before, "dds.sec.auth.builtin.PKI-DH.identity_certificate"),
            "file://" + (dir / "driver" / "cert.pem").string());
  EXPECT_EQ(value(before, "dds.sec.access.builtin.Access-Permissions.governance"),
            "file://" + (dir / "governance.p7s").string());
  EXPECT_FALSE(value(before, crl_property).has_value()) << "no CRL before any rotation";
  { std::ofstream(dir / "ca" / "crl.pem") << "-----BEGIN X509 CRL-----\n"; }
  EXPECT_EQ(value(SecurityProperties({dir.string(), "driver"}), crl_property),
            "file://" + (dir / "ca" / "crl.pem").string());
  EXPECT_THROW(SecurityProperties({dir.string(), "operator"}), BusError);  // no such identity here
  EXPECT_THROW(SecurityProperties({dir.string(), "../driver"}), BusError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace dpc::bus

namespace dpc::bus {
namespace {

constexpr int kRawDomain = 69;

uint64_t WallNs() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<uint64_t>(t.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(t.tv_nsec);
}

TEST(RawReaderTest, DeliversEachPayloadAsItArrivedForKeyedTopics) {
  BusParticipant publishing(BusOptions{kRawDomain, "dpc_bus_test_raw_writer", {}});
  BusParticipant recording(BusOptions{kRawDomain, "dpc_bus_test_recorder", {}});
  auto sample_reader = recording.MakeRawReader<msg::StokesSample>("bench1");
  auto command_reader = recording.MakeRawReader<msg::WaveplateCommand>("bench1");
  auto sample_writer = publishing.MakeWriter<msg::StokesSample>("bench1");
  auto command_writer = publishing.MakeWriter<msg::WaveplateCommand>("bench1", "main");
  ASSERT_TRUE(Eventually([&] {
    return sample_reader->counters().matched_writers == 1 && command_reader->counters().matched_writers == 1;
  }, 10s)) << "a raw reader matches the typed writers (same type name, keyed)";

  msg::StokesSample sample;
  sample.bench_id("bench1");
  sample.sequence_number(41);
  sample.s_out({0.0, 0.6, 0.8});
  msg::WaveplateCommand command;
  command.bench_id("bench1");
  command.controller_id("main");
  command.answers_sample(41);
  std::vector<RawSample> samples, commands;
  const uint64_t before_ns = WallNs();
  ASSERT_TRUE(Eventually([&] {
    sample_writer->Write(sample);
    command_writer->Write(command);
    sample_reader->TakeAll(&samples);
    command_reader->TakeAll(&commands);
    return !samples.empty() && !commands.empty();
  }, 10s));
  const uint64_t after_ns = WallNs();
  // Both times are this host's wall clock, within the test's span, the reception after the source.
  EXPECT_GE(samples.front().source_time_ns, before_ns - 1'000'000);
  EXPECT_LE(samples.front().source_time_ns, samples.front().reception_time_ns);
  EXPECT_LE(samples.front().reception_time_ns, after_ns + 1'000'000);
  EXPECT_EQ(sample_reader->lost(), 0u);
  // The exact bytes the writer's type support serialized, encapsulation header included.
  EXPECT_EQ(samples.front().bytes, EncodeRaw(sample));
  EXPECT_EQ(commands.front().bytes, EncodeRaw(command));
  ASSERT_GE(samples.front().bytes.size(), 4u);
  EXPECT_EQ(samples.front().bytes[0], '\0');
  EXPECT_EQ(samples.front().bytes[1], '\1') << "CDR, little endian";
}

}  // namespace
}  // namespace dpc::bus
