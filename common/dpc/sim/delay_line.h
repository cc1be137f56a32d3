#pragma once
// The loop delay between the controller and the waveplates: a ring of D commands.
//
// Slot k mod D holds the command issued at sample k − D, which the plant applies at sample k;
// after reading it, the controller's command of sample k goes into the same slot. A sample whose
// update failed (or that comes before activation) issues no new command: its slot then carries
// the latest one, copied only when the slot holds an older one. Commands are stored as poses
// (whatever the loop needs per command: the sines and cosines of its angles), computed once
// when issued.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dpc {

template <typename Pose>
class DelayLine {
 public:
  /// D ≥ 1 slots, all holding `initial`.
  DelayLine(int64_t delay_samples, const Pose& initial)
      : poses_(static_cast<std::size_t>(delay_samples), initial),
        versions_(static_cast<std::size_t>(delay_samples), 0),
        latest_(delay_samples - 1) {}

  int64_t size() const { return static_cast<int64_t>(poses_.size()); }
  /// Real-time. The command applied at the sample whose slot this is.
  const Pose& at(int64_t slot) const { return poses_[static_cast<std::size_t>(slot)]; }
  /// Real-time. The controller's latest command.
  const Pose& latest() const { return poses_[static_cast<std::size_t>(latest_)]; }
  /// Real-time. Where the command of the sample of `slot` is written (may alias latest() when
  /// D = 1: read what you need from latest() first, element by element).
  Pose& issue(int64_t slot) { return poses_[static_cast<std::size_t>(slot)]; }

  /// Real-time. Ends the controller's sample of `slot`: `issued` tells whether a new command
  /// was written with issue(slot); if not, the slot takes the latest command.
  void Close(int64_t slot, bool issued) {
    const std::size_t s = static_cast<std::size_t>(slot);
    if (issued) {
      versions_[s] = ++version_;
    } else if (versions_[s] != version_) {
      poses_[s] = poses_[static_cast<std::size_t>(latest_)];
      versions_[s] = version_;
    }
    latest_ = slot;
  }

  /// The slot after `slot`.
  int64_t Next(int64_t slot) const { return slot + 1 == size() ? 0 : slot + 1; }

 private:
  std::vector<Pose> poses_;
  std::vector<uint64_t> versions_;  ///< version of the command each slot holds
  uint64_t version_ = 0;            ///< of the latest command
  int64_t latest_;
};

}  // namespace dpc
