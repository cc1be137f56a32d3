#pragma once
// One DDS participant of the bench, its typed writers and readers, QoS from XML profiles.
//
// Profiles: the file named by FASTRTPS_DEFAULT_PROFILES_FILE (the variable Fast DDS 2.9 reads);
// when it is unset, the shipped loopback-only profile (deploy/fastdds/loopback.xml), so that no
// default configuration talks to the network. The participant QoS is the profile
// "dpc.participant"; each topic's writer and reader QoS are "<topic>.writer" / "<topic>.reader"
// (topics.h). A missing file or profile is an error that names it: nothing starts with
// unintended QoS. Every writer and reader lives in its bench's partition (topics.h).
//
// Security (BusOptions::security, a directory made by deploy/security/make-bench-pki.sh and an
// identity in it): the participant authenticates with PKI-DH, is checked against the signed
// governance and its identity's signed permissions (Access-Permissions), and protects what
// the governance says with AES-GCM-GMAC. Without credentials, or with an identity that may not
// publish or read a topic in a partition, nothing is matched.

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "dpc/bench/source_binding.h"
#include "dpc/bus/topics.h"

namespace dpc::bus {

/// Fast DDS refused something (a profile, an entity); the message says what and where.
class BusError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The environment variable Fast DDS 2.9 reads its XML profiles from.
inline constexpr char kProfilesEnvironmentVariable[] = "FASTRTPS_DEFAULT_PROFILES_FILE";
/// The participant profile every process uses.
inline constexpr char kParticipantProfile[] = "dpc.participant";

/// The profiles file in effect: $FASTRTPS_DEFAULT_PROFILES_FILE, else the shipped loopback
/// profile (found next to the source tree or the installed share directory). Throws BusError if
/// neither exists.
std::string ResolveProfilesFile();

/// DDS Security credentials: a bench's security directory (make-bench-pki.sh) and the identity
/// in it this participant is (driver, polarimeter, controller-<id>, operator, observer).
struct SecurityOptions {
  std::string directory;  ///< empty: security off
  std::string identity;
  bool enabled() const { return !directory.empty(); }
};

/// The Fast DDS participant properties that turn on the builtin security plugins with these
/// credentials (file:// URIs). Throws BusError naming a missing file.
std::vector<std::pair<std::string, std::string>> SecurityProperties(const SecurityOptions& security);

/// Something that happened to a remote participant: discovered (announced; on a secure bench
/// authentication follows), authenticated, gone (left or lease expired), or refused by DDS
/// Security's authentication (not of the bench's CA, expired, revoked, or a handshake that
/// failed; reported once per participant, though Fast DDS refuses it at each announcement).
struct PeerEvent {
  enum class Kind { kDiscovered, kGone, kAuthenticated, kRefused };
  Kind kind;
  std::string guid;  ///< the remote participant's GUID prefix, as SourceName writes it
  std::string name;  ///< its participant name ("dpc-driver/bench1"); empty if unknown
};
/// A remote participant's name as it may be logged: control characters (newlines, terminal
/// escapes) replaced by '?', at most 64 bytes (then "…"). A peer chooses its name freely.
std::string PrintableName(const std::string& name);
/// "participant refused by DDS Security (…): 01.0f.… (dpc-driver/bench1)".
std::string Describe(const PeerEvent& event);
/// An on_peer that hands each event to `sink` as (whether it is a refusal, Describe(event)).
std::function<void(const PeerEvent&)> DescribedPeerEvents(std::function<void(bool refusal, const std::string&)> sink);

struct BusOptions {
  int domain_id = 0;
  std::string participant_name = "dpc";
  SecurityOptions security;
};

/// Counters of one reader, readable from any thread.
struct ReaderCounters {
  std::atomic<uint64_t> samples{0};          ///< delivered to the callback
  std::atomic<uint64_t> other_benches{0};    ///< samples of another bench_id, skipped
  std::atomic<uint64_t> deadline_misses{0};  ///< DDS requested-deadline misses
  std::atomic<int> matched_writers{0};
};

template <typename Message>
class Writer {
 public:
  Writer(eprosima::fastdds::dds::DataWriter* writer, eprosima::fastdds::dds::Publisher* publisher)
      : writer_(writer), publisher_(publisher) {}
  ~Writer() { publisher_->delete_datawriter(writer_); }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Thread-safe (Fast DDS serializes writes). False if Fast DDS refused the sample.
  bool Write(const Message& message) {
    return writer_->write(const_cast<Message*>(&message));
  }
  int matched_readers() const {
    eprosima::fastdds::dds::PublicationMatchedStatus status;
    writer_->get_publication_matched_status(status);
    return status.current_count;
  }
  eprosima::fastdds::dds::DataWriter* raw() const { return writer_; }

 private:
  eprosima::fastdds::dds::DataWriter* writer_;
  eprosima::fastdds::dds::Publisher* publisher_;
};

/// Delivers every valid sample of one topic to a callback, on Fast DDS's listener thread.
/// With a bench id, samples of other benches are counted and skipped.
template <typename Message>
class Reader : public eprosima::fastdds::dds::DataReaderListener {
 public:
  using Callback = std::function<void(const Message&, const eprosima::fastdds::dds::SampleInfo&)>;

  Reader(std::string bench_id, Callback callback)
      : bench_id_(std::move(bench_id)), callback_(std::move(callback)) {}
  ~Reader() override {
    if (reader_ != nullptr) {
      reader_->set_listener(nullptr);
      subscriber_->delete_datareader(reader_);
    }
  }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  void Attach(eprosima::fastdds::dds::DataReader* reader,
              eprosima::fastdds::dds::Subscriber* subscriber) {
    reader_ = reader;
    subscriber_ = subscriber;
  }

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override {
    eprosima::fastdds::dds::SampleInfo info;
    while (reader->take_next_sample(&message_, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      if (!bench_id_.empty() && bench_id_ != message_.bench_id().to_string()) {
        counters_.other_benches.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      counters_.samples.fetch_add(1, std::memory_order_relaxed);
      callback_(message_, info);
    }
  }
  void on_requested_deadline_missed(
      eprosima::fastdds::dds::DataReader*,
      const eprosima::fastdds::dds::RequestedDeadlineMissedStatus&) override {
    counters_.deadline_misses.fetch_add(1, std::memory_order_relaxed);
  }
  void on_subscription_matched(
      eprosima::fastdds::dds::DataReader*,
      const eprosima::fastdds::dds::SubscriptionMatchedStatus& status) override {
    counters_.matched_writers.store(status.current_count, std::memory_order_relaxed);
  }

  const ReaderCounters& counters() const { return counters_; }
  eprosima::fastdds::dds::DataReader* raw() const { return reader_; }

 private:
  std::string bench_id_;
  Callback callback_;
  Message message_;  ///< taken into; only the listener thread touches it
  ReaderCounters counters_;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
};

/// A participant's GUID prefix as a SourceId (what SourceBinding judges and SourceName prints).
inline SourceId SourceOf(const eprosima::fastrtps::rtps::GuidPrefix_t& prefix) {
  SourceId id{};
  static_assert(sizeof(prefix.value) == std::tuple_size_v<SourceId>);
  for (size_t i = 0; i < id.size(); ++i) id[i] = prefix.value[i];
  return id;
}
/// The participant that wrote a received sample.
inline SourceId SourceOf(const eprosima::fastdds::dds::SampleInfo& info) {
  return SourceOf(info.sample_identity.writer_guid().guidPrefix);
}

class BusParticipant {
 public:
  /// Loads the profiles (ResolveProfilesFile) and creates the participant. Throws BusError.
  /// `on_peer` is called from Fast DDS's threads for every PeerEvent (keep it short; it may
  /// log). Empty: none.
  explicit BusParticipant(const BusOptions& options, std::function<void(const PeerEvent&)> on_peer = nullptr);
  ~BusParticipant();
  BusParticipant(const BusParticipant&) = delete;
  BusParticipant& operator=(const BusParticipant&) = delete;

  /// A writer with the topic's "<topic>.writer" profile in the partition of `bench_id` (and, for
  /// a command, of `controller_id`: topics.h).
  template <typename Message>
  std::unique_ptr<Writer<Message>> MakeWriter(const std::string& bench_id, const std::string& controller_id = {}) {
    using Traits = TopicTraits<Message>;
    auto* topic = TopicFor(std::string(Traits::kTopic),
                           eprosima::fastdds::dds::TypeSupport(new typename Traits::PubSubType()));
    auto* publisher = PublisherFor(PartitionFor<Message>(bench_id, controller_id));
    auto* writer = CreateWriter(publisher, topic, std::string(Traits::kWriterProfile));
    return std::make_unique<Writer<Message>>(writer, publisher);
  }

  /// A reader with the topic's "<topic>.reader" profile in the partition of `bench_id` (every
  /// controller's, for commands); `callback` runs on Fast DDS's listener thread for each valid
  /// sample of `bench_id` (all benches if empty).
  template <typename Message>
  std::unique_ptr<Reader<Message>> MakeReader(const std::string& bench_id,
                                              typename Reader<Message>::Callback callback) {
    using Traits = TopicTraits<Message>;
    auto* topic = TopicFor(std::string(Traits::kTopic),
                           eprosima::fastdds::dds::TypeSupport(new typename Traits::PubSubType()));
    auto* subscriber = SubscriberFor(PartitionFor<Message>(bench_id));
    auto reader = std::make_unique<Reader<Message>>(bench_id, std::move(callback));
    reader->Attach(CreateReader(subscriber, topic, std::string(Traits::kReaderProfile), reader.get()), subscriber);
    return reader;
  }

  /// The partition a remote writer (SampleInfo::sample_identity.writer_guid()) was discovered
  /// in; "" if it is not (or no longer) known.
  std::string WriterPartition(const eprosima::fastrtps::rtps::GUID_t& writer) const;

  eprosima::fastdds::dds::DomainParticipant* raw() const { return participant_; }
  const std::string& profiles_file() const { return profiles_file_; }
  bool secure() const { return secure_; }

 private:
  eprosima::fastdds::dds::Topic* TopicFor(const std::string& name,
                                          eprosima::fastdds::dds::TypeSupport type);
  eprosima::fastdds::dds::Publisher* PublisherFor(const std::string& partition);
  eprosima::fastdds::dds::Subscriber* SubscriberFor(const std::string& partition);
  eprosima::fastdds::dds::DataWriter* CreateWriter(eprosima::fastdds::dds::Publisher* publisher,
                                                   eprosima::fastdds::dds::Topic* topic,
                                                   const std::string& profile);
  eprosima::fastdds::dds::DataReader* CreateReader(eprosima::fastdds::dds::Subscriber* subscriber,
                                                   eprosima::fastdds::dds::Topic* topic,
                                                   const std::string& profile,
                                                   eprosima::fastdds::dds::DataReaderListener* listener);

  class DiscoveryListener;
  std::string profiles_file_;
  bool secure_ = false;
  std::unique_ptr<DiscoveryListener> discovery_;  ///< remote writers' partitions
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  std::mutex mutex_;
  std::vector<eprosima::fastdds::dds::Topic*> topics_;
  std::map<std::string, eprosima::fastdds::dds::Publisher*> publishers_;    ///< by partition
  std::map<std::string, eprosima::fastdds::dds::Subscriber*> subscribers_;  ///< by partition
};

}  // namespace dpc::bus
