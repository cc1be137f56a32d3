#include "dpc/bus/bus_participant.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string_view>
#include <type_traits>
#include <utility>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastrtps/attributes/LibrarySettingsAttributes.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/UDPv6TransportDescriptor.h>
#include <fmt/format.h>

#include "dpc/bench/clock.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/bus/shm_segments.h"

namespace dpc::bus {
namespace fdds = eprosima::fastdds::dds;

namespace {

std::string ExecutableDirectory() {
  std::error_code error;
  const auto path = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::string() : path.parent_path().string();
}

std::string FileUri(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    throw BusError(fmt::format("security: {} is missing (make it with deploy/security/make-bench-pki.sh)",
                               path.string()));
  }
  return "file://" + std::filesystem::absolute(path).lexically_normal().string();
}

std::string FirstName(const fdds::PartitionQosPolicy& partition) {
  const auto names = partition.names();
  return names.empty() ? std::string("(default)") : names.front();
}

constexpr std::string_view kBenchPrefix = "dpc.";
constexpr std::string_view kControllerInfix = ".controller.";

/// A remote participant as the logs name it: "GUID prefix (name)", or the prefix alone.
std::string Who(const std::string& guid, const std::string& name) {
  return name.empty() ? guid : fmt::format("{} ({})", guid, name);
}

}  // namespace

std::string BenchPartition(const std::string& bench_id) {
  return std::string(kBenchPrefix) + (bench_id.empty() ? "*" : bench_id);
}

std::string ControllerPartition(const std::string& bench_id, const std::string& controller_id) {
  return BenchPartition(bench_id) + std::string(kControllerInfix) + (controller_id.empty() ? "*" : controller_id);
}

std::string ControllerOfPartition(const std::string& bench_id, const std::string& partition) {
  const std::string prefix = BenchPartition(bench_id) + std::string(kControllerInfix);
  if (bench_id.empty() || partition.size() <= prefix.size() || partition.compare(0, prefix.size(), prefix) != 0) {
    return {};
  }
  std::string id = partition.substr(prefix.size());
  if (id.find_first_of("*?[]") != std::string::npos) return {};
  return id;
}

std::vector<std::pair<std::string, std::string>> SecurityProperties(const SecurityOptions& security) {
  if (!security.enabled()) return {};
  if (security.identity.empty() || security.identity.find('/') != std::string::npos ||
      security.identity.front() == '.') {
    throw BusError(fmt::format("security: bad identity \"{}\" (driver, polarimeter, controller-<id>, "
                               "operator or observer)", security.identity));
  }
  const std::filesystem::path dir(security.directory);
  const std::string ca = FileUri(dir / "ca" / "ca.cert.pem");
  const std::filesystem::path mine = dir / security.identity;
  if (!std::filesystem::is_directory(mine)) {
    throw BusError(fmt::format("security: no identity \"{}\" in {}", security.identity, security.directory));
  }
  const std::string auth = "dds.sec.auth.builtin.PKI-DH.";
  const std::string access = "dds.sec.access.builtin.Access-Permissions.";
  std::vector<std::pair<std::string, std::string>> properties = {
      {"dds.sec.auth.plugin", "builtin.PKI-DH"},
      {auth + "identity_ca", ca},
      {auth + "identity_certificate", FileUri(mine / "cert.pem")},
      {auth + "private_key", FileUri(mine / "key.pem")},
      {"dds.sec.access.plugin", "builtin.Access-Permissions"},
      {access + "permissions_ca", ca},
      {access + "governance", FileUri(dir / "governance.p7s")},
      {access + "permissions", FileUri(mine / "permissions.p7s")},
      {"dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC"},
  };
  // Certificates replaced by a rotation are revoked (make-bench-pki.sh --rotate).
  if (const auto crl = dir / "ca" / "crl.pem"; std::filesystem::exists(crl)) {
    properties.emplace_back(auth + "identity_crl", FileUri(crl));
  }
  return properties;
}

/// Keeps the partition of every remote writer discovered (for the driver's identity binding:
/// a command's controller id must be its writer's partition's). Bounded: a participant that
/// announces writers beyond kMaxWriters gets none remembered (its commands are refused).
class BusParticipant::DiscoveryListener : public fdds::DomainParticipantListener {
 public:
  static constexpr size_t kMaxWriters = 4096;
  static constexpr size_t kMaxNames = 4096;
  /// `secure`: handshakes are tracked (PendingHandshakes).
  DiscoveryListener(std::function<void(const PeerEvent&)> on_peer, bool secure)
      : on_peer_(std::move(on_peer)), secure_(secure) {}

  void on_participant_discovery(fdds::DomainParticipant*,
                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
    using Status = eprosima::fastrtps::rtps::ParticipantDiscoveryInfo::DISCOVERY_STATUS;
    const auto prefix = info.info.m_guid.guidPrefix;
    std::string name = PrintableName(info.info.m_participantName.to_string());
    PeerEvent::Kind kind = PeerEvent::Kind::kDiscovered;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (info.status == Status::DISCOVERED_PARTICIPANT || info.status == Status::CHANGED_QOS_PARTICIPANT) {
        if (names_.size() < kMaxNames || names_.count(prefix) != 0) names_[prefix] = name;
        left_.erase(prefix);
        if (info.status == Status::CHANGED_QOS_PARTICIPANT) return;
        // Its handshake begins (unless its outcome came first: another thread of Fast DDS's).
        if (secure_ && settled_.count(prefix) == 0 && pending_.size() < kMaxNames) {
          pending_.emplace(prefix, Pending{MonotonicNs(), dropped_.erase(prefix) != 0});
        }
      } else {
        names_.erase(prefix);
        refused_.erase(prefix);
        pending_.erase(prefix);
        // Its lease expired (it left without saying so): if it comes back with the same GUID, it
        // may still hold the handshake it had with this participant (HandshakeWatchdog).
        if (secure_ && info.status == Status::DROPPED_PARTICIPANT && authenticated_.count(prefix) != 0 &&
            dropped_.size() < kMaxNames) {
          dropped_.insert(prefix);
        }
        settled_.erase(prefix);
        authenticated_.erase(prefix);
        if (left_.size() >= kMaxNames) left_.clear();  // forgetting only delays a rebinding
        left_.insert(prefix);
        kind = PeerEvent::Kind::kGone;
      }
    }
    if (on_peer_) on_peer_(PeerEvent{kind, SourceName(SourceOf(prefix)), std::move(name)});
  }
  void onParticipantAuthentication(fdds::DomainParticipant*,
                                   eprosima::fastrtps::rtps::ParticipantAuthenticationInfo&& info) override {
    using Status = eprosima::fastrtps::rtps::ParticipantAuthenticationInfo::AUTHENTICATION_STATUS;
    const auto prefix = info.guid.guidPrefix;
    const bool refused = info.status != Status::AUTHORIZED_PARTICIPANT;
    std::string name;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (auto found = names_.find(prefix); found != names_.end()) name = found->second;
      pending_.erase(prefix);
      if (settled_.size() < kMaxNames) settled_.insert(prefix);
      if (refused) {
        authenticated_.erase(prefix);
      } else if (authenticated_.size() < kMaxNames) {
        authenticated_.insert(prefix);
      }
      // A refused participant is handshaken and refused again at each of its announcements
      // (every second): it is reported once, until it is gone.
      if (refused) {
        if (refused_.count(prefix) != 0 || refused_.size() >= kMaxNames) return;
        refused_.insert(prefix);
      } else {
        refused_.erase(prefix);
      }
    }
    if (on_peer_) {
      on_peer_(PeerEvent{refused ? PeerEvent::Kind::kRefused : PeerEvent::Kind::kAuthenticated,
                         SourceName(SourceOf(prefix)), std::move(name)});
    }
  }
  void on_publisher_discovery(fdds::DomainParticipant*, eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override {
    using Status = eprosima::fastrtps::rtps::WriterDiscoveryInfo::DISCOVERY_STATUS;
    std::lock_guard<std::mutex> lock(mutex_);
    if (info.status == Status::REMOVED_WRITER) {
      partitions_.erase(info.info.guid());
      return;
    }
    const auto names = info.info.m_qos.m_partition.names();
    if (partitions_.size() >= kMaxWriters && partitions_.count(info.info.guid()) == 0) return;
    // A writer in several partitions names none (an honest writer of the bench is in one).
    partitions_[info.info.guid()] = names.size() == 1 ? names.front() : std::string();
  }
  std::string PartitionOf(const eprosima::fastrtps::rtps::GUID_t& writer) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto found = partitions_.find(writer);
    return found == partitions_.end() ? std::string() : found->second;
  }
  std::vector<std::string> AuthenticatedPeers() const {
    std::vector<std::string> peers;
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& prefix : authenticated_) peers.push_back(SourceName(SourceOf(prefix)));
    return peers;
  }
  bool HasLeft(const eprosima::fastrtps::rtps::GuidPrefix_t& prefix) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return left_.count(prefix) != 0;
  }
  std::vector<std::string> PendingHandshakes(int64_t older_than_ns, bool returning_only) const {
    const int64_t now_ns = MonotonicNs();
    std::vector<std::string> peers;
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [prefix, pending] : pending_) {
      if (now_ns - pending.since_ns < older_than_ns || (returning_only && !pending.returning)) continue;
      const auto name = names_.find(prefix);
      peers.push_back(Who(SourceName(SourceOf(prefix)), name == names_.end() ? std::string() : name->second));
    }
    return peers;
  }

 private:
  std::function<void(const PeerEvent&)> on_peer_;
  const bool secure_;
  mutable std::mutex mutex_;
  std::map<eprosima::fastrtps::rtps::GUID_t, std::string> partitions_;
  std::map<eprosima::fastrtps::rtps::GuidPrefix_t, std::string> names_;  ///< bounded by kMaxNames
  std::set<eprosima::fastrtps::rtps::GuidPrefix_t> refused_;            ///< reported; bounded by kMaxNames
  /// Secure only: discovered participants whose handshake has no outcome yet, since when
  /// (MonotonicNs); and those whose handshake had one (authenticated or refused). Both
  /// bounded by kMaxNames; a participant gone leaves both.
  struct Pending {
    int64_t since_ns;  ///< MonotonicNs
    bool returning;    ///< discovered again after its lease expired (dropped_)
  };
  std::map<eprosima::fastrtps::rtps::GuidPrefix_t, Pending> pending_;
  std::set<eprosima::fastrtps::rtps::GuidPrefix_t> settled_;
  /// Secure only: those authenticated (a subset of settled_).
  std::set<eprosima::fastrtps::rtps::GuidPrefix_t> authenticated_;
  /// Secure only: authenticated participants whose lease expired, until they come back.
  /// Bounded by kMaxNames.
  std::set<eprosima::fastrtps::rtps::GuidPrefix_t> dropped_;
  /// Participants reported gone (left or lease expired), until discovered again (HasLeft).
  /// Bounded by kMaxNames: emptied when full.
  std::set<eprosima::fastrtps::rtps::GuidPrefix_t> left_;
};

std::string PrintableName(const std::string& name) {
  constexpr size_t kMaxBytes = 64;
  std::string out = PrintableText(name.substr(0, kMaxBytes));
  if (name.size() > kMaxBytes) out += "…";
  return out;
}

std::string Describe(const PeerEvent& event) {
  const std::string who = Who(event.guid, event.name);
  switch (event.kind) {
    case PeerEvent::Kind::kDiscovered: return "participant discovered: " + who;
    case PeerEvent::Kind::kGone: return "participant gone: " + who;
    case PeerEvent::Kind::kAuthenticated: return "participant authenticated: " + who;
    case PeerEvent::Kind::kRefused:
      return "participant refused by DDS Security (not of this bench's CA, expired, revoked, or a failed "
             "handshake): " + who;
  }
  return who;
}

std::function<void(const PeerEvent&)> DescribedPeerEvents(std::function<void(bool, const std::string&)> sink) {
  return [sink = std::move(sink)](const PeerEvent& event) {
    sink(event.kind == PeerEvent::Kind::kRefused, Describe(event));
  };
}

namespace {

/// The profile's UDP transports with at least `bytes` of receive buffer (copies: the profile's
/// descriptors are shared by every participant made from it).
void RaiseUdpReceiveBuffers(fdds::DomainParticipantQos& qos, uint32_t bytes) {
  namespace rtps = eprosima::fastdds::rtps;
  for (auto& transport : qos.transport().user_transports) {
    const auto raised = [&](auto typed) -> std::shared_ptr<rtps::TransportDescriptorInterface> {
      if (typed == nullptr || typed->receiveBufferSize >= bytes) return nullptr;
      auto copy = std::make_shared<std::remove_cv_t<typename decltype(typed)::element_type>>(*typed);
      copy->receiveBufferSize = bytes;
      return copy;
    };
    auto copy = raised(std::dynamic_pointer_cast<rtps::UDPv4TransportDescriptor>(transport));
    if (copy == nullptr) copy = raised(std::dynamic_pointer_cast<rtps::UDPv6TransportDescriptor>(transport));
    if (copy != nullptr) transport = copy;
  }
}

std::string Mebibytes(uint64_t bytes) { return fmt::format("{:.1f} MiB", static_cast<double>(bytes) / 1048576.0); }

}  // namespace

uint64_t KernelUdpReceiveBufferLimitBytes() {
  std::ifstream file("/proc/sys/net/core/rmem_max");
  uint64_t bytes = 0;
  if (!(file >> bytes)) return 0;
  return bytes;
}

uint64_t GrantedUdpReceiveBufferBytes(uint64_t requested_bytes, uint64_t kernel_limit_bytes) {
  return kernel_limit_bytes > 0 ? std::min(requested_bytes, kernel_limit_bytes) : requested_bytes;
}

std::string UdpReceiveBufferNote(uint64_t requested_bytes, uint64_t kernel_limit_bytes) {
  if (kernel_limit_bytes == 0) {
    return fmt::format("UDP receive buffer: {} asked (the kernel's limit, net.core.rmem_max, could not be read)",
                       Mebibytes(requested_bytes));
  }
  const uint64_t granted_bytes = GrantedUdpReceiveBufferBytes(requested_bytes, kernel_limit_bytes);
  if (granted_bytes == requested_bytes) return fmt::format("UDP receive buffer: {}", Mebibytes(requested_bytes));
  return fmt::format(
      "UDP receive buffer: {} asked, but the kernel grants {} (net.core.rmem_max): at high rates messages may be "
      "lost while this process is not scheduled; to raise it: sysctl -w net.core.rmem_max={}",
      Mebibytes(requested_bytes), Mebibytes(granted_bytes), requested_bytes);
}

std::string ResolveProfilesFile() {
  if (const char* file = std::getenv(kProfilesEnvironmentVariable); file != nullptr && *file) {
    if (!std::filesystem::is_regular_file(file)) {
      throw BusError(fmt::format("{}={}: no such file", kProfilesEnvironmentVariable, file));
    }
    return file;
  }
  // The shipped loopback-only profile: installed next to the binaries, or in the source tree.
  std::vector<std::string> candidates;
  const std::string exe_dir = ExecutableDirectory();
  if (!exe_dir.empty()) candidates.push_back(exe_dir + "/../share/dpc/fastdds/loopback.xml");
#ifdef DPC_DEFAULT_PROFILES_FILE
  candidates.push_back(DPC_DEFAULT_PROFILES_FILE);
#endif
  for (const std::string& candidate : candidates) {
    if (std::filesystem::is_regular_file(candidate)) {
      return std::filesystem::weakly_canonical(candidate).string();
    }
  }
  throw BusError(fmt::format(
      "no Fast DDS profiles: set {} to an XML profiles file (see deploy/fastdds/loopback.xml)",
      kProfilesEnvironmentVariable));
}

BusParticipant::BusParticipant(const BusOptions& options, std::function<void(const PeerEvent&)> on_peer)
    : profiles_file_(ResolveProfilesFile()) {
  if (options.domain_id < 0 || options.domain_id > 232) {
    throw BusError(fmt::format("domain {} out of range: DDS domains are 0…232", options.domain_id));
  }
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  // Fast DDS reads the variable in load_profiles(); set it so that a default run uses the same
  // file we report.
  setenv(kProfilesEnvironmentVariable, profiles_file_.c_str(), 1);
  if (factory->load_profiles() != ReturnCode_t::RETCODE_OK) {
    throw BusError(fmt::format("{}: Fast DDS could not load this XML profiles file", profiles_file_));
  }
  fdds::DomainParticipantQos qos;
  if (factory->get_participant_qos_from_profile(kParticipantProfile, qos) != ReturnCode_t::RETCODE_OK) {
    throw BusError(fmt::format("{}: no participant profile \"{}\"", profiles_file_, kParticipantProfile));
  }
  qos.name(options.participant_name);
  if (options.udp_receive_buffer_bytes > 0) RaiseUdpReceiveBuffers(qos, options.udp_receive_buffer_bytes);
  for (const auto& [name, value] : SecurityProperties(options.security)) {
    qos.properties().properties().emplace_back(name, value);
  }
  secure_ = options.security.enabled();
  if (secure_) {
    // A secured reload runs the new participant beside the old one, authenticated with each
    // other, and then deletes the old one (ParticipantMaker::Reload). Without intraprocess
    // delivery what one sends the other (its goodbye, handshake and crypto messages) goes
    // through the transports and is taken on the receiver's own threads, never inside the
    // sender's Fast DDS locks on the sender's thread. (A move of the endpoints that never
    // completed, with no log line from the old participant's deletion, was seen once in about
    // sixty secured reloads with intraprocess delivery on; none since in the security process
    // tests.) The setting is Fast DDS's, process-wide; a secured service has one participant.
    eprosima::fastrtps::LibrarySettingsAttributes library;
    library.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
    eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(library);
  }
  // What a killed process left in /dev/shm delays the discovery of the one that replaces it.
  if (ProfilesUseSharedMemory(profiles_file_)) shm_cleanup_ = RemoveStaleShmFiles();
  discovery_ = std::make_unique<DiscoveryListener>(std::move(on_peer), secure_);
  participant_ = factory->create_participant(options.domain_id, qos, discovery_.get(), fdds::StatusMask::none());
  if (participant_ == nullptr) {
    throw BusError(secure_ ? fmt::format("Fast DDS could not create a secure participant on domain {} as \"{}\" "
                                         "with {}: are the certificate, key, governance and permissions of "
                                         "one bench CA, signed, and in date?",
                                         options.domain_id, options.security.identity, options.security.directory)
                           : fmt::format("Fast DDS could not create a participant on domain {} with {}",
                                         options.domain_id, profiles_file_));
  }
  canary_ = std::make_unique<EventThreadCanary>(participant_);
}

std::vector<std::string> BusParticipant::AuthenticatedPeers() const { return discovery_->AuthenticatedPeers(); }

bool BusParticipant::HasLeft(const SourceId& source) const { return discovery_->HasLeft(PrefixOf(source)); }

bool BusParticipant::AcceptFrom(SourceBinding* binding, const SourceId& source) const {
  return binding->Accept(source, MonotonicNs(), [this](const SourceId& bound) { return HasLeft(bound); });
}

std::string BusParticipant::guid_prefix() const { return SourceName(SourceOf(participant_->guid().guidPrefix)); }

std::vector<std::string> BusParticipant::PendingHandshakes(int64_t older_than_ns, bool returning_only) const {
  return discovery_->PendingHandshakes(older_than_ns, returning_only);
}

std::string BusParticipant::WriterPartition(const eprosima::fastrtps::rtps::GUID_t& writer) const {
  return discovery_->PartitionOf(writer);
}

fdds::Publisher* BusParticipant::PublisherFor(const std::string& partition) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto found = publishers_.find(partition);
  if (found != publishers_.end()) return found->second;
  fdds::PublisherQos qos = fdds::PUBLISHER_QOS_DEFAULT;
  qos.partition().push_back(partition.c_str());
  fdds::Publisher* publisher = participant_->create_publisher(qos);
  if (publisher == nullptr) throw BusError(fmt::format("Fast DDS could not create a publisher in partition {}", partition));
  publishers_.emplace(partition, publisher);
  return publisher;
}

fdds::Subscriber* BusParticipant::SubscriberFor(const std::string& partition) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto found = subscribers_.find(partition);
  if (found != subscribers_.end()) return found->second;
  fdds::SubscriberQos qos = fdds::SUBSCRIBER_QOS_DEFAULT;
  qos.partition().push_back(partition.c_str());
  fdds::Subscriber* subscriber = participant_->create_subscriber(qos);
  if (subscriber == nullptr) {
    throw BusError(fmt::format("Fast DDS could not create a subscriber in partition {}", partition));
  }
  subscribers_.emplace(partition, subscriber);
  return subscriber;
}

BusParticipant::~BusParticipant() {
  if (participant_ == nullptr) return;
  canary_.reset();
  // Writers and readers delete their own entities; whatever is left goes here.
  participant_->delete_contained_entities();
  fdds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

fdds::Topic* BusParticipant::TopicFor(const std::string& name, fdds::TypeSupport type) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (fdds::Topic* topic : topics_) {
    if (topic->get_name() == name) return topic;
  }
  if (type.register_type(participant_) != ReturnCode_t::RETCODE_OK &&
      participant_->find_type(type.get_type_name()).empty()) {
    throw BusError(fmt::format("could not register type {}", type.get_type_name()));
  }
  fdds::Topic* topic = participant_->create_topic(name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  if (topic == nullptr) throw BusError(fmt::format("could not create topic {}", name));
  topics_.push_back(topic);
  return topic;
}

fdds::DataWriter* BusParticipant::CreateWriter(fdds::Publisher* publisher, fdds::Topic* topic,
                                               const std::string& profile) {
  fdds::DataWriterQos qos;
  if (publisher->get_datawriter_qos_from_profile(profile, qos) != ReturnCode_t::RETCODE_OK) {
    throw BusError(fmt::format("{}: no data_writer profile \"{}\"", profiles_file_, profile));
  }
  fdds::DataWriter* writer = publisher->create_datawriter(topic, qos);
  if (writer == nullptr) {
    throw BusError(fmt::format("could not create a writer on {} in partition {} with profile {}{}", topic->get_name(),
                               FirstName(publisher->get_qos().partition()),
                               profile, secure_ ? " (does this identity's permissions allow it?)" : ""));
  }
  return writer;
}

fdds::DataReader* BusParticipant::CreateReader(fdds::Subscriber* subscriber, fdds::Topic* topic,
                                               const std::string& profile, fdds::DataReaderListener* listener,
                                               const std::function<void(fdds::DataReaderQos&)>& adjust) {
  fdds::DataReaderQos qos;
  if (subscriber->get_datareader_qos_from_profile(profile, qos) != ReturnCode_t::RETCODE_OK) {
    throw BusError(fmt::format("{}: no data_reader profile \"{}\"", profiles_file_, profile));
  }
  if (adjust) adjust(qos);
  fdds::DataReader* reader = subscriber->create_datareader(topic, qos, listener);
  if (reader == nullptr) {
    throw BusError(fmt::format("could not create a reader on {} in partition {} with profile {}{}", topic->get_name(),
                               FirstName(subscriber->get_qos().partition()),
                               profile, secure_ ? " (does this identity's permissions allow it?)" : ""));
  }
  return reader;
}

}  // namespace dpc::bus
