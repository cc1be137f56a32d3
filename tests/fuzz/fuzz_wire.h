#pragma once
// The message targets' input: a payload as a reader of the bus receives it.

#include <cstdint>
#include <cstring>

#include <fastcdr/exceptions/Exception.h>
#include <fastdds/rtps/common/SerializedPayload.h>

#include "dpc/bus/topics.h"
#include "fuzz_support.h"

namespace dpc::fuzz {

/// Deserializes `data` into `message` as a reader of the bus does: the payload (encapsulation
/// and CDR) through the PubSubType the bus registers for the topic (bus/topics.h). False if it
/// does not deserialize (the PubSubType says so). A Fast CDR exception that escapes is a
/// finding (cdr-exception); any other exception escapes to libFuzzer (a crash).
template <typename Message>
bool FromWire(const uint8_t* data, size_t size, Message* message) {
  using PubSubType = typename bus::TopicTraits<Message>::PubSubType;
  static PubSubType type;
  // Exactly the input's bytes: a read past the payload is a read past the allocation.
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<uint32_t>(size));
  if (size > 0) std::memcpy(payload.data, data, size);
  payload.length = static_cast<uint32_t>(size);
  try {
    return type.deserialize(&payload, message);
  } catch (const eprosima::fastcdr::exception::Exception& e) {
    DPC_FUZZ_CHECK(false, "cdr-exception",
                   "the generated PubSubType of %s let a Fast CDR exception out of deserialize: \"%s\" (on the bus "
                   "it escapes into Fast DDS's receive thread: std::terminate, the service aborts)",
                   type.getName(), e.what());
    return false;
  }
}

/// The control count a device that passed validation can have, chosen by a field of the
/// message (its sequence number) so that the input stays a payload a peer can send: 1 …
/// kMaxControls (the core's bound; the IDL's MAX_CONTROLS is lower).
inline int ControlCountFor(uint64_t selector) {
  return 1 + static_cast<int>(selector % static_cast<uint64_t>(kMaxControls));
}

}  // namespace dpc::fuzz
