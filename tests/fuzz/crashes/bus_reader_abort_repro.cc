// The cdr-exception finding over a real bus (README.md here): a peer writes one raw payload on a
// StokesSample topic (a raw type under the same type name); the reader is the generated
// StokesSamplePubSubType with a listener like dpc::bus::Reader's. Domain 177, not the bench's.
//
//   G=build-fuzz/idl/generated/dpc/msg   (or build/…: any build that ran fastddsgen)
//   g++ -std=c++17 -O1 -I$G/../.. -I$G bus_reader_abort_repro.cc $G/bench.cxx $G/benchPubSubTypes.cxx \
//       -lfastrtps -lfastcdr -lpthread -o repro
//   ./repro reader & ./repro writer bool     # or: encapsulation, truncated (the reader lives 15 s)
//
// bool / encapsulation: the reader aborts (exit 134, "terminate called after throwing an
// instance of 'eprosima::fastcdr::exception::BadParamException'"). truncated: the reader
// survives and the sample is dropped (the NotEnoughMemoryException the generated code catches).
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include "dpc/msg/bench.h"
#include "dpc/msg/benchPubSubTypes.h"
using namespace eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::SerializedPayload_t;
using eprosima::fastrtps::rtps::InstanceHandle_t;

class RawType : public TopicDataType {
 public:
  RawType() { setName("dpc::msg::StokesSample"); m_typeSize = 4096; m_isGetKeyDefined = true; }
  bool serialize(void* data, SerializedPayload_t* payload) override {
    auto* s = static_cast<std::string*>(data);
    std::memcpy(payload->data, s->data(), s->size());
    payload->length = s->size();
    payload->encapsulation = s->size() > 1 && (*s)[1] == 1 ? CDR_LE : CDR_BE;
    return true;
  }
  bool deserialize(SerializedPayload_t*, void*) override { return false; }
  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    auto* s = static_cast<std::string*>(data);
    return [s]() { return static_cast<uint32_t>(s->size()); };
  }
  void* createData() override { return new std::string(); }
  void deleteData(void* d) override { delete static_cast<std::string*>(d); }
  bool getKey(void*, InstanceHandle_t* h, bool) override { std::memset(h->value, 0, 16); h->value[0] = 1; return true; }
};

struct Listener : DataReaderListener {
  dpc::msg::StokesSample message_;
  void on_data_available(DataReader* reader) override {
    SampleInfo info;
    while (reader->take_next_sample(&message_, &info) == ReturnCode_t::RETCODE_OK) {
      std::printf("reader: took a sample, valid_data=%d bench_id='%s' seq=%llu s_in[0]=%g lockstep=%d\n",
                  info.valid_data, message_.bench_id().c_str(), (unsigned long long)message_.sequence_number(),
                  message_.s_in()[0], message_.lockstep());
      std::fflush(stdout);
    }
  }
};

std::string Valid(uint64_t seq) {
  dpc::msg::StokesSample m;
  m.bench_id("bench"); m.sequence_number(seq); m.s_in({1, 0, 0}); m.s_out({0, 0.6, 0.8}); m.lockstep(true);
  dpc::msg::StokesSamplePubSubType t;
  SerializedPayload_t p(t.getSerializedSizeProvider(&m)());
  t.serialize(&m, &p);
  return std::string(reinterpret_cast<char*>(p.data), p.length);
}

int main(int argc, char** argv) {
  const int domain = 177;
  auto* factory = DomainParticipantFactory::get_instance();
  auto* participant = factory->create_participant(domain, PARTICIPANT_QOS_DEFAULT);
  TypeSupport type(std::string(argv[1]) == "reader" ? static_cast<TopicDataType*>(new dpc::msg::StokesSamplePubSubType())
                                                  : new RawType());
  type.register_type(participant);
  auto* topic = participant->create_topic("wirecheck", "dpc::msg::StokesSample", TOPIC_QOS_DEFAULT);
  if (std::string(argv[1]) == "reader") {
    Listener listener;
    auto* sub = participant->create_subscriber(SUBSCRIBER_QOS_DEFAULT);
    DataReaderQos q = DATAREADER_QOS_DEFAULT;
    q.reliability().kind = RELIABLE_RELIABILITY_QOS;
    q.history().kind = KEEP_ALL_HISTORY_QOS;
    sub->create_datareader(topic, q, &listener);
    std::this_thread::sleep_for(std::chrono::seconds(15));
    std::printf("reader: alive at the end\n");
    return 0;
  }
  auto* pub = participant->create_publisher(PUBLISHER_QOS_DEFAULT);
  DataWriterQos q = DATAWRITER_QOS_DEFAULT;
  q.reliability().kind = RELIABLE_RELIABILITY_QOS;
  q.history().kind = KEEP_ALL_HISTORY_QOS;
  auto* writer = pub->create_datawriter(topic, q);
  // Wait for the reader (discovery), then give it a valid sample and the malformed one.
  PublicationMatchedStatus matched;
  for (int i = 0; i < 200 && (writer->get_publication_matched_status(matched), matched.current_count == 0); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const std::string mode = argv[2];
  std::string bytes = Valid(7);
  writer->write(&bytes);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  if (mode == "truncated") bytes = Valid(8).substr(0, 4 + 4 + 6 + 2);  // encapsulation + "bench" only
  if (mode == "bool") { bytes = Valid(9); bytes[bytes.size() - 1] = 2; }   // lockstep = 2
  if (mode == "encapsulation") { bytes = Valid(10); bytes[0] = 1; }
  writer->write(&bytes);
  std::printf("writer: wrote %s (%zu bytes)\n", mode.c_str(), bytes.size());
  std::fflush(stdout);
  std::this_thread::sleep_for(std::chrono::seconds(3));
  return 0;
}
