#pragma once
// The bench's target, with the driver as its one authority: it publishes the scenario's target
// as revision 1 and decides every request to change it (dpc target → dpc_target_request): a
// valid target is accepted as the next revision, anything else is refused with the reason. The
// revision grows with every accepted change, so controllers and the polarimeter keep the
// newest.

#include <cstdint>
#include <string>

#include "dpc/bench/bench_messages.h"
#include "dpc/config/scenario_config.h"

namespace dpc::services {

class TargetAuthority {
 public:
  struct Reply {
    bool accepted = false;
    uint64_t revision = 0;   ///< the new revision (accepted) or the current one (refused)
    std::string message;
  };

  /// `initial`: the scenario's target, validated (ValidateTargetConfig).
  explicit TargetAuthority(const TargetConfig& initial);

  const BenchTarget& current() const { return current_; }

  /// A request for `target`: accepted as the next revision if it is valid, else refused with
  /// the field that is wrong.
  Reply Request(const std::string& request_id, const TargetConfig& target);
  /// A request that could not even be read (`reason`, e.g. an unknown kind): refused.
  Reply Refuse(const std::string& request_id, const std::string& reason);

 private:
  BenchTarget current_;
};

}  // namespace dpc::services
