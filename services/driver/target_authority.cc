#include "target_authority.h"

#include <chrono>

#include <fmt/format.h>

#include "dpc/config/scenario_error.h"
#include "dpc/config/scenario_validation.h"

namespace dpc::services {

TargetAuthority::TargetAuthority(const TargetConfig& initial, uint32_t epoch) {
  current_.revision = (static_cast<uint64_t>(epoch) << 32) | 1u;
  current_.target = initial;
}

uint32_t TargetAuthority::EpochNow() {
  return static_cast<uint32_t>(std::chrono::duration_cast<std::chrono::seconds>(
                                   std::chrono::system_clock::now().time_since_epoch())
                                   .count());
}

TargetAuthority::Reply TargetAuthority::Request(const std::string& request_id, const TargetConfig& target) {
  try {
    ValidateTargetConfig(target);
  } catch (const ScenarioError& e) {
    return Refuse(request_id, e.what());
  }
  ++current_.revision;
  current_.request_id = request_id;
  current_.target = target;
  return Reply{true, current_.revision, fmt::format("target revision {}", current_.revision)};
}

TargetAuthority::Reply TargetAuthority::Refuse(const std::string&, const std::string& reason) {
  return Reply{false, current_.revision, reason};
}

}  // namespace dpc::services
