#pragma once
// The bench's topics: name, type and the XML profiles that give their QoS.
//
// | topic                  | type               | writer(s)            | QoS (deploy/fastdds/*.xml)        |
// |------------------------|--------------------|----------------------|-----------------------------------|
// | dpc_stokes_sample      | StokesSample       | polarimeter          | best effort, keep last 1, deadline|
// | dpc_waveplate_command  | WaveplateCommand   | controllers          | best effort, keep last 1, deadline|
// | dpc_waveplate_state    | WaveplateState     | driver               | best effort, keep last 1, deadline|
// | dpc_controller_status  | ControllerStatus   | controllers          | reliable, keep last 1, deadline   |
// | dpc_device_description | DeviceDescription  | driver               | reliable, transient local         |
// | dpc_target             | Target             | driver               | reliable, transient local         |
// | dpc_target_request     | TargetRequest      | dpc target           | reliable, volatile                |
// | dpc_target_reply       | TargetReply        | driver               | reliable, volatile                |
// | dpc_bench_summary      | BenchSummary       | polarimeter          | reliable, keep last 1, deadline   |
//
// Every profile is named "<topic>.writer" / "<topic>.reader"; data-sharing is off in all of them.
// Writers offer the profile's deadline; a reader requests it only with DeadlineWatch::kOn.
//
// Partitions: every topic of bench B lives in the DDS partition "dpc.B", except the controllers'
// commands: controller C writes in "dpc.B.controller.C", the driver reads "dpc.B.controller.*".
// A participant of another bench is never matched (its data never reaches this bench's
// readers: no cost, no instance taken), and with DDS Security the permissions grant a
// controller identity only its own partition, which binds the controller id to the identity
// (the driver refuses a command whose id is not its writer's partition's).

#include <string>
#include <string_view>

#include <fastcdr/exceptions/Exception.h>

#include "dpc/msg/bench.h"
#include "dpc/msg/benchPubSubTypes.h"

namespace dpc::bus {

/// The generated type support, made safe against hostile payloads: fastddsgen 2.3.0's
/// deserialize catches only Fast CDR's NotEnoughMemoryException, and a BadParamException (an
/// encapsulation byte that is not 0, an unknown encapsulation kind, a boolean that is neither 0
/// nor 1) went up through Fast DDS's receive thread and ended the process with std::terminate
/// (one datagram from anyone aborted any service). Here every Fast CDR exception drops the
/// sample, as a truncated payload already did. (Fixed upstream in Fast-DDS-Gen, eProsima
/// Fast-DDS-Gen#168; tests/fuzz found it.)
template <typename Generated>
class SafePubSubType : public Generated {
 public:
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    try {
      return Generated::deserialize(payload, data);
    } catch (const eprosima::fastcdr::exception::Exception&) {
      return false;
    }
  }
};

template <typename Message>
struct TopicTraits;

#define DPC_BUS_TOPIC(Message, topic_name, per_controller)                  \
  template <>                                                               \
  struct TopicTraits<msg::Message> {                                        \
    using PubSubType = SafePubSubType<msg::Message##PubSubType>;            \
    static constexpr std::string_view kTopic = topic_name;                  \
    static constexpr std::string_view kWriterProfile = topic_name ".writer"; \
    static constexpr std::string_view kReaderProfile = topic_name ".reader"; \
    static constexpr bool kPerController = per_controller;                  \
  }

DPC_BUS_TOPIC(StokesSample, "dpc_stokes_sample", false);
DPC_BUS_TOPIC(WaveplateCommand, "dpc_waveplate_command", true);
DPC_BUS_TOPIC(WaveplateState, "dpc_waveplate_state", false);
DPC_BUS_TOPIC(ControllerStatus, "dpc_controller_status", false);
DPC_BUS_TOPIC(DeviceDescription, "dpc_device_description", false);
DPC_BUS_TOPIC(Target, "dpc_target", false);
DPC_BUS_TOPIC(TargetRequest, "dpc_target_request", false);
DPC_BUS_TOPIC(TargetReply, "dpc_target_reply", false);
DPC_BUS_TOPIC(BenchSummary, "dpc_bench_summary", false);

#undef DPC_BUS_TOPIC

/// "dpc.<bench>"; every bench ("dpc.*") for "".
std::string BenchPartition(const std::string& bench_id);
/// "dpc.<bench>.controller.<controller>"; "*" for an empty bench or controller.
std::string ControllerPartition(const std::string& bench_id, const std::string& controller_id);
/// The controller id a command writer's partition names ("" if it names none or a pattern).
std::string ControllerOfPartition(const std::string& bench_id, const std::string& partition);
/// The partition of a writer or reader of `Message` for this bench (and controller).
template <typename Message>
std::string PartitionFor(const std::string& bench_id, const std::string& controller_id = {}) {
  return TopicTraits<Message>::kPerController ? ControllerPartition(bench_id, controller_id) : BenchPartition(bench_id);
}

}  // namespace dpc::bus
