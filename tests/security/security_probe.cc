// A standalone probe of Fast DDS 2.9's builtin DDS Security with the files that
// deploy/security/make-bench-pki.sh makes. It needs none of the project's types: it
// publishes or subscribes a one-struct type of its own ("dpc_probe::Sample", a counter and a
// short text) on any topic name, so a pair of probes shows what the governance and the
// permissions allow between two identities.
//
//   security_probe --dir DIR --identity NAME|none --role pub|sub --topic T --partition P
//                  --domain D --seconds S [--verbose]
//
// The participant is LOOPBACK ONLY: UDPv4 with interfaceWhiteList 127.0.0.1, no builtin
// transports (no SHM, nothing on another interface), and unicast discovery with the initial
// peer 127.0.0.1 (no multicast locator at all). --identity none creates a participant with no
// security properties. --partition may be a comma-separated list.
// The publisher writes a sample every 50 ms for S seconds; the subscriber counts what it reads.
// Output, one line on stdout:
//   identity=driver role=pub topic=... partition=... domain=200 created=yes matched=1
//   first_match_ms=812 written=40 received=0
// created=no:<entity> when the participant, publisher/subscriber, topic or endpoint could not
// be created (security refused it); exit 0 when the probe ran, 3 when creation failed, 2 on a
// usage error. first_match_ms is from the process start; -1 if never matched.
// Build (not part of the CMake build):
//   g++ -O1 -std=c++17 -o /tmp/security_probe tests/security/security_probe.cc -lfastrtps -lfastcdr
// tests/security/run_security_check.sh builds it and runs the cases.

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/log/StdoutErrConsumer.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

using namespace eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::SerializedPayload_t;
using eprosima::fastrtps::rtps::InstanceHandle_t;
using eprosima::fastrtps::rtps::Locator_t;
using eprosima::fastrtps::rtps::IPLocator;

namespace {

using Clock = std::chrono::steady_clock;
const Clock::time_point kStart = Clock::now();
long long MsSinceStart() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - kStart).count();
}

// The sample: a counter and up to 63 characters of text, serialized as XCDR1 (@final).
struct Sample {
  uint32_t counter = 0;
  std::string text;
};
constexpr uint32_t kMaxText = 63;

class SampleType : public TopicDataType {
 public:
  SampleType() {
    setName("dpc_probe::Sample");
    m_typeSize = 4 /*encapsulation*/ + 4 + 4 + kMaxText + 1 + 3;
    m_isGetKeyDefined = false;
  }
  bool serialize(void* data, SerializedPayload_t* payload) override {
    auto* sample = static_cast<Sample*>(data);
    eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->max_size);
    eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
    payload->encapsulation = cdr.endianness() == eprosima::fastcdr::Cdr::BIG_ENDIANNESS ? CDR_BE : CDR_LE;
    try {
      cdr.serialize_encapsulation();
      cdr << sample->counter << sample->text.substr(0, kMaxText);
    } catch (...) {
      return false;
    }
    payload->length = static_cast<uint32_t>(cdr.getSerializedDataLength());
    return true;
  }
  bool deserialize(SerializedPayload_t* payload, void* data) override {
    auto* sample = static_cast<Sample*>(data);
    eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->length);
    eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
    try {
      cdr.read_encapsulation();
      payload->encapsulation = cdr.endianness() == eprosima::fastcdr::Cdr::BIG_ENDIANNESS ? CDR_BE : CDR_LE;
      cdr >> sample->counter >> sample->text;
    } catch (...) {
      return false;
    }
    return true;
  }
  std::function<uint32_t()> getSerializedSizeProvider(void*) override {
    return [this] { return m_typeSize; };
  }
  void* createData() override { return new Sample(); }
  void deleteData(void* data) override { delete static_cast<Sample*>(data); }
  bool getKey(void*, InstanceHandle_t*, bool) override { return false; }
};

struct Options {
  std::string dir, identity, role, topic, partition;
  int domain = -1;
  double seconds = 5;
  bool verbose = false;
};

int Usage(const char* why) {
  std::fprintf(stderr,
               "security_probe: %s\nusage: security_probe --dir DIR --identity NAME|none --role pub|sub "
               "--topic T --partition P[,P...] --domain D --seconds S [--verbose]\n",
               why);
  return 2;
}

std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream stream(text);
  for (std::string part; std::getline(stream, part, ',');) parts.push_back(part);
  return parts;
}

std::atomic<int> g_matched{0};      // current count
std::atomic<int> g_max_matched{0};  // highest current count seen
std::atomic<long long> g_first_match_ms{-1};
std::atomic<long long> g_received{0};

void NoteMatch(int current) {
  g_matched = current;
  if (current > g_max_matched) g_max_matched = current;
  long long none = -1;
  if (current > 0) g_first_match_ms.compare_exchange_strong(none, MsSinceStart());
}

class WriterListener : public DataWriterListener {
  void on_publication_matched(DataWriter*, const PublicationMatchedStatus& status) override {
    NoteMatch(status.current_count);
  }
};
class ReaderListener : public DataReaderListener {
  void on_subscription_matched(DataReader*, const SubscriptionMatchedStatus& status) override {
    NoteMatch(status.current_count);
  }
  void on_data_available(DataReader* reader) override {
    Sample sample;
    SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
      if (info.valid_data) ++g_received;
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--verbose") {
      options.verbose = true;
      continue;
    }
    if (i + 1 >= argc) return Usage(("missing value of " + arg).c_str());
    std::string value = argv[++i];
    if (arg == "--dir") options.dir = value;
    else if (arg == "--identity") options.identity = value;
    else if (arg == "--role") options.role = value;
    else if (arg == "--topic") options.topic = value;
    else if (arg == "--partition") options.partition = value;
    else if (arg == "--domain") options.domain = std::stoi(value);
    else if (arg == "--seconds") options.seconds = std::stod(value);
    else return Usage(("unknown argument " + arg).c_str());
  }
  if (options.identity.empty() || options.topic.empty() || (options.role != "pub" && options.role != "sub") ||
      options.domain < 0 || options.domain > 232 || (options.identity != "none" && options.dir.empty())) {
    return Usage("missing or bad arguments");
  }

  Log::ClearConsumers();
  Log::RegisterConsumer(std::make_unique<StdoutErrConsumer>());
  Log::SetVerbosity(options.verbose ? Log::Info : Log::Error);

  DomainParticipantQos pqos = PARTICIPANT_QOS_DEFAULT;
  pqos.name("security_probe." + options.identity);
  pqos.transport().use_builtin_transports = false;
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList.push_back("127.0.0.1");
  pqos.transport().user_transports.push_back(udp);
  Locator_t loopback;
  IPLocator::setIPv4(loopback, 127, 0, 0, 1);
  auto& builtin = pqos.wire_protocol().builtin;
  builtin.initialPeersList.clear();
  builtin.initialPeersList.push_back(loopback);  // ports of participant ids 0..3 are probed
  builtin.metatrafficMulticastLocatorList.clear();
  builtin.metatrafficUnicastLocatorList.clear();
  builtin.metatrafficUnicastLocatorList.push_back(loopback);
  pqos.wire_protocol().default_unicast_locator_list.push_back(loopback);
  builtin.discovery_config.leaseDuration = {5, 0};
  builtin.discovery_config.leaseDuration_announcementperiod = {1, 0};

  if (options.identity != "none") {
    const std::string dir = "file://" + options.dir + "/";
    const std::string me = dir + options.identity + "/";
    auto& props = pqos.properties().properties();
    props.emplace_back("dds.sec.auth.plugin", "builtin.PKI-DH");
    props.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_ca", dir + "ca/ca.cert.pem");
    props.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_certificate", me + "cert.pem");
    props.emplace_back("dds.sec.auth.builtin.PKI-DH.private_key", me + "key.pem");
    props.emplace_back("dds.sec.access.plugin", "builtin.Access-Permissions");
    props.emplace_back("dds.sec.access.builtin.Access-Permissions.permissions_ca", dir + "ca/ca.cert.pem");
    props.emplace_back("dds.sec.access.builtin.Access-Permissions.governance", dir + "governance.p7s");
    props.emplace_back("dds.sec.access.builtin.Access-Permissions.permissions", me + "permissions.p7s");
    props.emplace_back("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
    if (std::ifstream(options.dir + "/ca/crl.pem").good()) {  // after make-bench-pki.sh --rotate
      props.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_crl", dir + "ca/crl.pem");
    }
  }

  std::string created = "yes";
  long long written = 0;
  auto* factory = DomainParticipantFactory::get_instance();
  DomainParticipant* participant = factory->create_participant(options.domain, pqos);
  WriterListener writer_listener;
  ReaderListener reader_listener;
  if (participant == nullptr) {
    created = "no:participant";
  } else {
    TypeSupport type(new SampleType());
    Topic* topic = nullptr;
    if (type.register_type(participant) != ReturnCode_t::RETCODE_OK ||
        (topic = participant->create_topic(options.topic, type.get_type_name(), TOPIC_QOS_DEFAULT)) == nullptr) {
      created = "no:topic";
    } else if (options.role == "pub") {
      PublisherQos qos = PUBLISHER_QOS_DEFAULT;
      for (const auto& name : Split(options.partition)) qos.partition().push_back(name.c_str());
      Publisher* publisher = participant->create_publisher(qos);
      DataWriterQos wqos = DATAWRITER_QOS_DEFAULT;
      wqos.reliability().kind = RELIABLE_RELIABILITY_QOS;
      wqos.durability().kind = VOLATILE_DURABILITY_QOS;
      wqos.history().kind = KEEP_LAST_HISTORY_QOS;
      wqos.history().depth = 1;
      wqos.data_sharing().off();
      DataWriter* writer = publisher ? publisher->create_datawriter(topic, wqos, &writer_listener) : nullptr;
      if (publisher == nullptr) {
        created = "no:publisher";
      } else if (writer == nullptr) {
        created = "no:datawriter";
      } else {
        Sample sample;
        const auto end = kStart + std::chrono::duration<double>(options.seconds);
        while (Clock::now() < end) {
          ++sample.counter;
          sample.text = options.identity + " #" + std::to_string(sample.counter);
          if (writer->write(&sample)) ++written;
          std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
      }
    } else {
      SubscriberQos qos = SUBSCRIBER_QOS_DEFAULT;
      for (const auto& name : Split(options.partition)) qos.partition().push_back(name.c_str());
      Subscriber* subscriber = participant->create_subscriber(qos);
      DataReaderQos rqos = DATAREADER_QOS_DEFAULT;
      rqos.reliability().kind = RELIABLE_RELIABILITY_QOS;
      rqos.durability().kind = VOLATILE_DURABILITY_QOS;
      rqos.history().kind = KEEP_LAST_HISTORY_QOS;
      rqos.history().depth = 100;
      rqos.data_sharing().off();
      DataReader* reader = subscriber ? subscriber->create_datareader(topic, rqos, &reader_listener) : nullptr;
      if (subscriber == nullptr) {
        created = "no:subscriber";
      } else if (reader == nullptr) {
        created = "no:datareader";
      } else {
        std::this_thread::sleep_until(kStart + std::chrono::duration<double>(options.seconds));
      }
    }
  }
  if (created != "yes") {
    // Keep a refused probe alive as long as a running one, so that its peer's result is not
    // affected by when it stops.
    std::this_thread::sleep_until(kStart + std::chrono::duration<double>(options.seconds));
  }
  std::printf("identity=%s role=%s topic=%s partition=%s domain=%d created=%s matched=%d matched_at_end=%d first_match_ms=%lld "
              "written=%lld received=%lld\n",
              options.identity.c_str(), options.role.c_str(), options.topic.c_str(), options.partition.c_str(),
              options.domain, created.c_str(), g_max_matched.load(), g_matched.load(), g_first_match_ms.load(), written,
              g_received.load());
  std::fflush(stdout);
  if (participant != nullptr) {
    participant->delete_contained_entities();
    factory->delete_participant(participant);
  }
  Log::Flush();
  return created == "yes" ? 0 : 3;
}
