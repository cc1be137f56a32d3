#pragma once
// The bench's target, with the driver as its one authority: it publishes the scenario's target
// as the first revision of its epoch and decides every request to change it (dpc target →
// dpc_target_request): a valid target is accepted as the next revision, anything else is
// refused with the reason. The revision grows with every accepted change, so controllers and
// the polarimeter keep the newest. A revision is epoch << 32 | count, the epoch the driver's
// start (wall-clock seconds): a restarted driver's revisions are above every one before, so its
// targets are never mistaken for old ones (a driver restarted with revision 1 again was ignored
// by controllers that had seen revision 2).

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

  /// `initial`: the scenario's target, validated (ValidateTargetConfig), published as revision
  /// epoch << 32 | 1.
  TargetAuthority(const TargetConfig& initial, uint32_t epoch);

  /// The epoch of a driver starting now: the wall clock's seconds.
  static uint32_t EpochNow();

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
