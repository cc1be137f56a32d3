#pragma once
// The bench's topics: name, type and the XML profiles that give their QoS.
//
// | topic                  | type               | writer(s)            | QoS (deploy/fastdds/*.xml)        |
// |------------------------|--------------------|----------------------|-----------------------------------|
// | dpc_stokes_sample      | StokesSample       | polarimeter          | reliable, keep last 1, deadline   |
// | dpc_waveplate_command  | WaveplateCommand   | controllers          | reliable, keep last 1, deadline   |
// | dpc_waveplate_state    | WaveplateState     | driver               | reliable, keep last 1, deadline   |
// | dpc_controller_status  | ControllerStatus   | controllers          | reliable, keep last 1, deadline   |
// | dpc_device_description | DeviceDescription  | driver               | reliable, transient local         |
// | dpc_target             | Target             | driver               | reliable, transient local         |
// | dpc_target_request     | TargetRequest      | dpc target           | reliable, volatile                |
// | dpc_target_reply       | TargetReply        | driver               | reliable, volatile                |
//
// Every profile is named "<topic>.writer" / "<topic>.reader"; data-sharing is off in all of them.

#include <string_view>

#include "dpc/msg/bench.h"
#include "dpc/msg/benchPubSubTypes.h"

namespace dpc::bus {

template <typename Message>
struct TopicTraits;

#define DPC_BUS_TOPIC(Message, topic_name)                                  \
  template <>                                                               \
  struct TopicTraits<msg::Message> {                                        \
    using PubSubType = msg::Message##PubSubType;                            \
    static constexpr std::string_view kTopic = topic_name;                  \
    static constexpr std::string_view kWriterProfile = topic_name ".writer"; \
    static constexpr std::string_view kReaderProfile = topic_name ".reader"; \
  }

DPC_BUS_TOPIC(StokesSample, "dpc_stokes_sample");
DPC_BUS_TOPIC(WaveplateCommand, "dpc_waveplate_command");
DPC_BUS_TOPIC(WaveplateState, "dpc_waveplate_state");
DPC_BUS_TOPIC(ControllerStatus, "dpc_controller_status");
DPC_BUS_TOPIC(DeviceDescription, "dpc_device_description");
DPC_BUS_TOPIC(Target, "dpc_target");
DPC_BUS_TOPIC(TargetRequest, "dpc_target_request");
DPC_BUS_TOPIC(TargetReply, "dpc_target_reply");

#undef DPC_BUS_TOPIC

}  // namespace dpc::bus
