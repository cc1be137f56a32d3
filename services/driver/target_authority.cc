#include "target_authority.h"

#include <fmt/format.h>

#include "dpc/config/scenario_error.h"
#include "dpc/config/scenario_validation.h"

namespace dpc::services {

TargetAuthority::TargetAuthority(const TargetConfig& initial) {
  current_.revision = 1;
  current_.target = initial;
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
