#pragma once
// The bench's topics as the `dpc` DDS tools see them: names, short aliases, type names, a
// dispatch from a topic name to its message type, and every message as text (one line) or JSON
// (one object with every IDL field; enums by their IDL name, strings as UTF-8, NaN as null).

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "dpc/bus/topics.h"

namespace dpc::tools {

struct BusTopic {
  std::string_view name;       ///< "dpc_waveplate_state"
  std::string_view alias;      ///< "state"
  std::string_view type_name;  ///< "dpc::msg::WaveplateState" (the registered DDS type name)
};

/// The 8 topics of common/dpc/bus/topics.h, in that order.
const std::vector<BusTopic>& BenchTopics();

/// The topic named `name`: its full name ("dpc_waveplate_state"), the name without the "dpc_"
/// prefix ("waveplate_state") or its alias ("state"). Case-sensitive.
std::optional<BusTopic> ResolveTopic(std::string_view name);

/// "dpc_stokes_sample (sample), dpc_waveplate_command (command), …" for error messages.
std::string DescribeValidTopics();

/// Calls `f(std::type_identity<msg::X>{})` with the message type of `topic` (a full topic name
/// from BenchTopics) and returns its result.
template <typename F>
decltype(auto) WithTopicMessage(std::string_view topic, F&& f) {
  if (topic == bus::TopicTraits<msg::StokesSample>::kTopic) return f(std::type_identity<msg::StokesSample>{});
  if (topic == bus::TopicTraits<msg::WaveplateCommand>::kTopic) return f(std::type_identity<msg::WaveplateCommand>{});
  if (topic == bus::TopicTraits<msg::WaveplateState>::kTopic) return f(std::type_identity<msg::WaveplateState>{});
  if (topic == bus::TopicTraits<msg::ControllerStatus>::kTopic) return f(std::type_identity<msg::ControllerStatus>{});
  if (topic == bus::TopicTraits<msg::DeviceDescription>::kTopic) return f(std::type_identity<msg::DeviceDescription>{});
  if (topic == bus::TopicTraits<msg::Target>::kTopic) return f(std::type_identity<msg::Target>{});
  if (topic == bus::TopicTraits<msg::TargetRequest>::kTopic) return f(std::type_identity<msg::TargetRequest>{});
  if (topic == bus::TopicTraits<msg::BenchSummary>::kTopic) return f(std::type_identity<msg::BenchSummary>{});
  return f(std::type_identity<msg::TargetReply>{});
}

const char* DriverModeName(msg::DriverMode mode);       ///< "DRIVER_ACTIVE"
const char* TargetKindName(msg::TargetKind kind);       ///< "TARGET_POINT"
const char* ControlMapKindName(msg::ControlMapKind kind);
const char* StageKindName(msg::StageKind kind);

/// Every field of the IDL type, in IDL order.
nlohmann::ordered_json ToJson(const msg::StokesSample& m);
nlohmann::ordered_json ToJson(const msg::WaveplateCommand& m);
nlohmann::ordered_json ToJson(const msg::WaveplateState& m);
nlohmann::ordered_json ToJson(const msg::ControllerStatus& m);
nlohmann::ordered_json ToJson(const msg::DeviceDescription& m);
nlohmann::ordered_json ToJson(const msg::Target& m);
nlohmann::ordered_json ToJson(const msg::TargetRequest& m);
nlohmann::ordered_json ToJson(const msg::TargetReply& m);
nlohmann::ordered_json ToJson(const msg::BenchSummary& m);

/// One readable line with the important fields and their units.
std::string ToText(const msg::StokesSample& m);
std::string ToText(const msg::WaveplateCommand& m);
std::string ToText(const msg::WaveplateState& m);
std::string ToText(const msg::ControllerStatus& m);
std::string ToText(const msg::DeviceDescription& m);
std::string ToText(const msg::Target& m);
std::string ToText(const msg::TargetRequest& m);
std::string ToText(const msg::TargetReply& m);
std::string ToText(const msg::BenchSummary& m);

/// "[+0.0000, +0.6000, +0.8000]" with `decimals` digits.
std::string FormatValues(const double* values, size_t count, int decimals = 4);

}  // namespace dpc::tools
