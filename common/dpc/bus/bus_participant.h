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

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
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
#include "dpc/bus/event_thread_canary.h"
#include "dpc/bus/shm_segments.h"
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
  /// At least this receive buffer (SO_RCVBUF) on the participant's UDP sockets, in bytes; 0:
  /// the profile's (or the kernel's default). What a receiver keeps while its threads are not
  /// scheduled: a recorder asks for more than a service (UdpReceiveBufferNote). The kernel
  /// caps it at net.core.rmem_max without saying so.
  uint32_t udp_receive_buffer_bytes = 0;
};

/// The largest UDP receive buffer the kernel grants an unprivileged socket
/// (/proc/sys/net/core/rmem_max), in bytes; 0 if it cannot be read.
uint64_t KernelUdpReceiveBufferLimitBytes();

/// The UDP receive buffer a socket that asks for `requested_bytes` gets: at most the kernel's
/// limit (KernelUdpReceiveBufferLimitBytes; 0, unknown: the request).
uint64_t GrantedUdpReceiveBufferBytes(uint64_t requested_bytes, uint64_t kernel_limit_bytes);

/// What a command that asked for `requested_bytes` of UDP receive buffer should tell its user,
/// given the kernel's limit (KernelUdpReceiveBufferLimitBytes): the buffer it gets, and if the
/// kernel caps it below the request, by how much and how to raise the limit.
std::string UdpReceiveBufferNote(uint64_t requested_bytes, uint64_t kernel_limit_bytes);

/// Whether a reader requests its topic's DEADLINE (the profile's period) and counts the misses.
/// Fast DDS re-arms a deadline timer for every sample a reader receives (and every one a writer
/// writes): on the 2-core development VM the profile's deadlines on every reader and writer took
/// half the bench's CPU per sample at 2 kHz (498 against 251 µs, `dpc_bus_benchmark --only
/// transport`). Only the readers whose misses a service reports request it; the writers offer
/// the profile's deadline (a reader that requests none matches a writer that offers one).
enum class DeadlineWatch {
  kOff,  ///< the reader requests no deadline (misses stay 0)
  kOn,   ///< the reader requests the profile's deadline; ReaderCounters::deadline_misses counts
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

/// A sample as it arrived on the wire: its serialized payload, CDR encapsulation header
/// included, untouched (what a recorder keeps), with the writer's source timestamp and the
/// reception time (CLOCK_REALTIME ns; 0 for a time before 1970).
struct RawSample {
  std::string bytes;
  uint64_t source_time_ns = 0;
  uint64_t reception_time_ns = 0;
};

/// Decodes a raw payload (RawSample::bytes) with `Message`'s real type support; false if it
/// does not decode.
template <typename Message>
bool DecodeRaw(const std::string& bytes, Message* message) {
  typename TopicTraits<Message>::PubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<uint32_t>(bytes.size()));
  std::memcpy(payload.data, bytes.data(), bytes.size());
  payload.length = static_cast<uint32_t>(bytes.size());
  return type.deserialize(&payload, message);
}

/// `message` serialized with its real type support, CDR encapsulation header included (what a
/// writer of it sends and RawSample::bytes holds).
template <typename Message>
std::string EncodeRaw(const Message& message) {
  typename TopicTraits<Message>::PubSubType type;
  Message copy = message;  // the type support takes a non-const pointer
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&copy)());
  if (!type.serialize(&copy, &payload)) return {};
  return std::string(reinterpret_cast<const char*>(payload.data), payload.length);
}

/// A pass-through type support registered under `Message`'s type name: a reader of it matches
/// the bench's writers of `Message` and hands over each payload's bytes as they arrived. Its
/// key (keyed topics) is the real type's, from the bytes. A participant uses either this or the
/// typed support of a topic, never both (one type name, one registration).
template <typename Message>
class RawPubSubType : public eprosima::fastdds::dds::TopicDataType {
 public:
  RawPubSubType() {
    setName(real_.getName());
    m_typeSize = real_.m_typeSize;
    m_isGetKeyDefined = real_.m_isGetKeyDefined;
  }
  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override {
    const std::string& bytes = static_cast<RawSample*>(data)->bytes;
    if (bytes.size() > payload->max_size) return false;
    std::memcpy(payload->data, bytes.data(), bytes.size());
    payload->length = static_cast<uint32_t>(bytes.size());
    return true;
  }
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    static_cast<RawSample*>(data)->bytes.assign(reinterpret_cast<const char*>(payload->data), payload->length);
    return true;
  }
  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] { return static_cast<uint32_t>(static_cast<RawSample*>(data)->bytes.size()); };
  }
  void* createData() override { return new RawSample(); }
  void deleteData(void* data) override { delete static_cast<RawSample*>(data); }
  bool getKey(void* data, eprosima::fastrtps::rtps::InstanceHandle_t* handle, bool force_md5) override {
    if (!m_isGetKeyDefined) return false;
    Message message;
    return DecodeRaw(static_cast<RawSample*>(data)->bytes, &message) && real_.getKey(&message, handle, force_md5);
  }

 private:
  typename TopicTraits<Message>::PubSubType real_;
};

/// A reader of one topic's raw payloads (RawPubSubType) that its owner drains with TakeAll()
/// (a recorder's writing loop), with no work per sample on Fast DDS's receive thread besides
/// storing it: no listener call, no deadline timer. Its history keeps kDepth samples per
/// instance between two takes. No bench filter: the partition is the bench's.
class RawReader : public eprosima::fastdds::dds::DataReaderListener {
 public:
  static constexpr int32_t kDepth = 8192;

  RawReader() = default;
  ~RawReader() override {
    if (reader_ != nullptr) {
      reader_->set_listener(nullptr);
      subscriber_->delete_datareader(reader_);
    }
  }
  RawReader(const RawReader&) = delete;
  RawReader& operator=(const RawReader&) = delete;

  /// A topic's reader QoS made a recorder's: no deadline (nothing to watch, no timer to re-arm
  /// per sample), KEEP_LAST kDepth per instance, the pool grown on demand.
  static void Qos(eprosima::fastdds::dds::DataReaderQos& qos) {
    qos.deadline().period = eprosima::fastrtps::c_TimeInfinite;
    qos.history().kind = eprosima::fastdds::dds::KEEP_LAST_HISTORY_QOS;
    qos.history().depth = kDepth;
    qos.resource_limits().max_samples_per_instance = kDepth;
    qos.resource_limits().max_samples = std::max(qos.resource_limits().max_instances, 1) * kDepth;
    qos.resource_limits().allocated_samples = 64;
  }

  void Attach(eprosima::fastdds::dds::DataReader* reader, eprosima::fastdds::dds::Subscriber* subscriber) {
    reader_ = reader;
    subscriber_ = subscriber;
  }
  /// Appends every sample waiting, oldest first (per instance), to `out`; returns how many.
  size_t TakeAll(std::vector<RawSample>* out) {
    size_t taken = 0;
    eprosima::fastdds::dds::SampleInfo info;
    while (reader_->take_next_sample(&sample_, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      sample_.source_time_ns = Ns(info.source_timestamp);
      sample_.reception_time_ns = Ns(info.reception_timestamp);
      out->push_back(std::move(sample_));
      sample_ = RawSample();
      ++taken;
    }
    counters_.samples.fetch_add(taken, std::memory_order_relaxed);
    return taken;
  }
  /// Samples Fast DDS reports lost on this reader (SampleLostStatus: sent by a matched writer,
  /// never received, e.g. dropped on the way).
  uint64_t lost() const {
    eprosima::fastdds::dds::SampleLostStatus status;
    reader_->get_sample_lost_status(status);
    return static_cast<uint64_t>(status.total_count);
  }
  void on_subscription_matched(eprosima::fastdds::dds::DataReader*,
                               const eprosima::fastdds::dds::SubscriptionMatchedStatus& status) override {
    counters_.matched_writers.store(status.current_count, std::memory_order_relaxed);
  }
  const ReaderCounters& counters() const { return counters_; }

 private:
  static uint64_t Ns(const eprosima::fastrtps::rtps::Time_t& t) {
    return t.seconds() < 0 ? 0 : static_cast<uint64_t>(t.seconds()) * 1'000'000'000ull + t.nanosec();
  }
  RawSample sample_;  ///< taken into
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
/// The GUID prefix of a SourceId (SourceOf's inverse).
inline eprosima::fastrtps::rtps::GuidPrefix_t PrefixOf(const SourceId& id) {
  eprosima::fastrtps::rtps::GuidPrefix_t prefix;
  for (size_t i = 0; i < id.size(); ++i) prefix.value[i] = id[i];
  return prefix;
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
  /// sample of `bench_id` (all benches if empty). With DeadlineWatch::kOff (the default) it
  /// requests no deadline whatever the profile says.
  template <typename Message>
  std::unique_ptr<Reader<Message>> MakeReader(const std::string& bench_id,
                                              typename Reader<Message>::Callback callback,
                                              DeadlineWatch deadline = DeadlineWatch::kOff) {
    using Traits = TopicTraits<Message>;
    auto* topic = TopicFor(std::string(Traits::kTopic),
                           eprosima::fastdds::dds::TypeSupport(new typename Traits::PubSubType()));
    auto* subscriber = SubscriberFor(PartitionFor<Message>(bench_id));
    auto reader = std::make_unique<Reader<Message>>(bench_id, std::move(callback));
    std::function<void(eprosima::fastdds::dds::DataReaderQos&)> adjust;
    if (deadline == DeadlineWatch::kOff) {
      adjust = [](eprosima::fastdds::dds::DataReaderQos& qos) {
        qos.deadline().period = eprosima::fastrtps::c_TimeInfinite;
      };
    }
    reader->Attach(CreateReader(subscriber, topic, std::string(Traits::kReaderProfile), reader.get(), adjust),
                   subscriber);
    return reader;
  }

  /// A reader of `Message`'s topic in the bench's partition (every controller's, for commands)
  /// that keeps each sample's payload as it arrived until RawReader::TakeAll (a recorder): the
  /// topic's reader profile, without its deadline, with a history of RawReader::kDepth.
  template <typename Message>
  std::unique_ptr<RawReader> MakeRawReader(const std::string& bench_id) {
    using Traits = TopicTraits<Message>;
    auto* topic = TopicFor(std::string(Traits::kTopic), eprosima::fastdds::dds::TypeSupport(new RawPubSubType<Message>()));
    auto* subscriber = SubscriberFor(PartitionFor<Message>(bench_id));
    auto reader = std::make_unique<RawReader>();
    reader->Attach(CreateReader(subscriber, topic, std::string(Traits::kReaderProfile), reader.get(), RawReader::Qos),
                   subscriber);
    return reader;
  }

  /// A writer of raw payloads (RawPubSubType, e.g. replayed from a recording) on `Message`'s
  /// topic with its writer profile, in the partition of `bench_id` (and `controller_id`, for
  /// commands). A payload is written as it is: its key is computed from it, nothing else checked.
  template <typename Message>
  std::unique_ptr<Writer<RawSample>> MakeRawWriter(const std::string& bench_id, const std::string& controller_id = {}) {
    using Traits = TopicTraits<Message>;
    auto* topic = TopicFor(std::string(Traits::kTopic), eprosima::fastdds::dds::TypeSupport(new RawPubSubType<Message>()));
    auto* publisher = PublisherFor(PartitionFor<Message>(bench_id, controller_id));
    return std::make_unique<Writer<RawSample>>(CreateWriter(publisher, topic, std::string(Traits::kWriterProfile)),
                                               publisher);
  }

  /// The partition a remote writer (SampleInfo::sample_identity.writer_guid()) was discovered
  /// in; "" if it is not (or no longer) known.
  std::string WriterPartition(const eprosima::fastrtps::rtps::GUID_t& writer) const;

  /// With DDS Security: the remote participants discovered at least `older_than_ns` ago (steady
  /// clock) whose handshake has had no outcome since (neither authenticated nor refused, nor
  /// gone), as "GUID prefix (name)"; with kReturningOnly, only those discovered again after
  /// their lease had expired. Empty on an open participant. (Fast DDS 2.9's handshake can stall
  /// for good: HandshakeWatchdog.)
  static constexpr bool kReturningOnly = true;
  std::vector<std::string> PendingHandshakes(int64_t older_than_ns, bool returning_only = false) const;

  /// With DDS Security: the remote participants authenticated (and not gone since), as GUID
  /// prefixes written as SourceName writes them. Empty on an open participant.
  std::vector<std::string> AuthenticatedPeers() const;

  /// Whether discovery reported the remote participant `source` gone (it left, or its lease
  /// expired) and has not discovered it since: what lets a service take a new source at once
  /// when the one it is bound to has left (SourceBinding). False for a participant never seen,
  /// and possibly for one gone among more than 4096 others since (the record is bounded).
  bool HasLeft(const SourceId& source) const;
  /// Whether `binding` takes a message of `source` heard now (MonotonicNs): SourceBinding::Accept,
  /// which asks HasLeft of its bound source only for a message it would refuse.
  bool AcceptFrom(SourceBinding* binding, const SourceId& source) const;

  /// This participant's GUID prefix, written as SourceName writes it.
  std::string guid_prefix() const;

  eprosima::fastdds::dds::DomainParticipant* raw() const { return participant_; }
  const std::string& profiles_file() const { return profiles_file_; }
  /// With a shared-memory profile: the stale Fast DDS files removed before the participant was
  /// created (RemoveStaleShmFiles); all zero otherwise.
  const StaleShmCleanup& shm_cleanup() const { return shm_cleanup_; }
  bool secure() const { return secure_; }

 private:
  eprosima::fastdds::dds::Topic* TopicFor(const std::string& name,
                                          eprosima::fastdds::dds::TypeSupport type);
  eprosima::fastdds::dds::Publisher* PublisherFor(const std::string& partition);
  eprosima::fastdds::dds::Subscriber* SubscriberFor(const std::string& partition);
  eprosima::fastdds::dds::DataWriter* CreateWriter(eprosima::fastdds::dds::Publisher* publisher,
                                                   eprosima::fastdds::dds::Topic* topic,
                                                   const std::string& profile);
  /// A reader with the QoS of `profile`, changed by `adjust` if given.
  eprosima::fastdds::dds::DataReader* CreateReader(
      eprosima::fastdds::dds::Subscriber* subscriber, eprosima::fastdds::dds::Topic* topic, const std::string& profile,
      eprosima::fastdds::dds::DataReaderListener* listener,
      const std::function<void(eprosima::fastdds::dds::DataReaderQos&)>& adjust = {});

  class DiscoveryListener;
  std::string profiles_file_;
  StaleShmCleanup shm_cleanup_;
  bool secure_ = false;
  std::unique_ptr<DiscoveryListener> discovery_;  ///< remote writers' partitions
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  std::unique_ptr<EventThreadCanary> canary_;  ///< ticks on participant_'s event thread
  std::mutex mutex_;
  std::vector<eprosima::fastdds::dds::Topic*> topics_;
  std::map<std::string, eprosima::fastdds::dds::Publisher*> publishers_;    ///< by partition
  std::map<std::string, eprosima::fastdds::dds::Subscriber*> subscribers_;  ///< by partition
};

}  // namespace dpc::bus
