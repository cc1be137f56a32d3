#pragma once
// Who a service takes the bench's authoritative data from: one source (a DDS participant, named by
// its 12-byte GUID prefix) at a time. With DDS Security the permissions already say who may write
// a topic (only the driver writes the target, the device description and the states; only the
// polarimeter writes samples). On an open domain anyone may write them, so a service binds to
// the first source it hears and refuses every other one while the bound source keeps talking:
// a forged target, device description, state or sample from another participant is refused and
// counted, whatever it says (a revision of 2⁶⁴−1, another device, a sequence number near 2⁶⁴).
//
// The binding is released when the bound source has been silent for `release_after_ns` (the
// driver publishes a state at least every holding heartbeat, 5 ms; the polarimeter a sample per
// period): a driver or polarimeter restarted after kill -9 is a new participant, and it is taken
// as soon as the old one has been quiet that long, without waiting for its DDS lease to expire.
// It is released at once when the service's discovery says the bound source has left (a driver
// reloaded for new credentials moves to a new participant and deletes the old one): the caller
// passes that test to Accept, which asks it only of a message it would otherwise refuse.
// What this cannot do on an open domain: tell a forger who speaks first, or who speaks while the
// real source is silent, from the real source. The services report every refused source; a
// bench reachable by untrusted peers runs with DDS Security.
//
// O(1), no allocation. Not thread-safe: the caller's lock guards it.

#include <array>
#include <cstdint>
#include <string>

#include <fmt/format.h>

namespace dpc {

/// A DDS participant's GUID prefix (12 bytes); all zero: unknown.
using SourceId = std::array<uint8_t, 12>;

inline std::string SourceName(const SourceId& id) {
  std::string text;
  for (size_t i = 0; i < id.size(); ++i) text += fmt::format("{}{:02x}", i > 0 && i % 4 == 0 ? "." : "", id[i]);
  return text;
}

/// The services' release time: 20 of the driver's holding heartbeats (5 ms), several sample
/// periods of any polarimeter above 30 Hz. (A slower polarimeter, or a machine stalled this long,
/// is only bound again to itself.)
inline constexpr int64_t kSourceReleaseNs = 100'000'000;

class SourceBinding {
 public:
  explicit SourceBinding(int64_t release_after_ns) : release_after_ns_(release_after_ns) {}

  /// Whether to take a message from `source` heard at `now_ns` (monotonic): yes from the bound
  /// source (or the first one, or any one once the bound source has been silent for the release
  /// time: it becomes the bound source); no from any other one (counted).
  bool Accept(const SourceId& source, int64_t now_ns) {
    if (bound_ && source == source_) {
      last_heard_ns_ = now_ns;
      return true;
    }
    if (!bound_ || now_ns - last_heard_ns_ > release_after_ns_) {
      if (bound_ || released_) ++rebinds_;
      released_ = false;
      bound_ = true;
      source_ = source;
      last_heard_ns_ = now_ns;
      return true;
    }
    ++refused_;
    last_refused_ = source;
    return false;
  }

  /// Accept, but first, for a message it would refuse, asks `has_left(bound source)` (e.g. the
  /// participant's BusParticipant::HasLeft): a bound source that left is released, and
  /// `source` taken at once.
  template <typename HasLeft>
  bool Accept(const SourceId& source, int64_t now_ns, HasLeft&& has_left) {
    if (bound_ && source != source_ && now_ns - last_heard_ns_ <= release_after_ns_ && has_left(source_)) Release();
    return Accept(source, now_ns);
  }

  /// Forgets the bound source (it left): the next message's source is taken, as a rebind.
  void Release() {
    if (!bound_) return;
    bound_ = false;
    released_ = true;
  }

  bool bound() const { return bound_; }
  const SourceId& source() const { return source_; }
  /// Messages refused from other sources.
  uint64_t refused() const { return refused_; }
  /// The source of the latest refused message.
  const SourceId& last_refused() const { return last_refused_; }
  /// Times the binding moved to a new source after the bound one fell silent or left.
  uint64_t rebinds() const { return rebinds_; }

  /// What the latest refusal was, for logs and status: "<what> from participant <refused>
  /// refused: the bench's <who> is <bound> (<n> refused so far)".
  std::string Refusal(const char* what, const char* who) const {
    return fmt::format("{} from participant {} refused: the bench's {} is {} ({} refused so far)", what,
                       SourceName(last_refused_), who, SourceName(source_), refused_);
  }

 private:
  int64_t release_after_ns_;
  bool bound_ = false;
  bool released_ = false;  ///< the bound source left (Release): the next binding is a rebind
  SourceId source_{};
  int64_t last_heard_ns_ = 0;
  uint64_t refused_ = 0;
  SourceId last_refused_{};
  uint64_t rebinds_ = 0;
};

}  // namespace dpc
