#pragma once
// When a secured service makes its DDS participant again by itself. Fast DDS 2.9's security
// handshake between two participants can stall for good: both have discovered each other,
// neither ever reports the other authenticated or refused, and no data flows between them (seen
// about once in twenty simultaneous starts, and once in about thirty reloads, on loopback). A new
// participant is handshaken afresh, which is what a restart or a SIGHUP did by hand.
//
// The watchdog asks for that only when both hold:
//   - a peer's handshake has had no outcome for kStallNs (BusParticipant::PendingHandshakes);
//   - the service has made no progress for kStallNs (the driver applied no command, the
//     controller wrote none, the polarimeter received no state): the stall costs the bench.
// A peer that never finishes a handshake on purpose therefore cannot make a working service
// reload; and a starved one reloads at most after kFirstBackoffNs, then after twice as long each
// time, up to kMaxBackoffNs, until it makes progress again (then a new stall heals after
// kStallNs again). Pure policy (no clock, no DDS): the service gives it the times and the
// stalled peers (ParticipantMaker::HandshakeStalled).
//
// A peer whose lease had expired (it was stopped, or cut off, for longer than its lease) and
// that comes back with the same GUID is another matter: it still holds the handshake it finished
// before, and Fast DDS 2.9 does not handshake it again, so its new handshake stays pending and it
// never hears from this participant again, while its own side sees nothing wrong (seen with a
// controller stopped for 5 s: the polarimeter it came back to never sent it a sample). Only a
// new participant here, a stranger to it, is handshaken afresh; so a returning peer pending for
// kStallNs makes a reload even when this service works (JudgeReturning). The new participant
// never saw the peer leave, so each returning peer costs at most one reload, and at most one such
// reload comes per kFirstBackoffNs.
//
// An observer (a `dpc` command: record, monitor, dashboard, topic) has no progress of its own to
// weigh: a stalled peer is one it hears nothing from, and its reload costs only its own view for
// about a second. Its `progress_ns` is when it last had no handshake pending (ObserverParticipant
// in tools/dpc/bus_tool_support.h), so any stall heals after kStallNs, the back-off runs while
// some handshake stays pending, and it starts over once none is.

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

namespace dpc::bus {

/// Peers for a log line: the first three, then how many more ("a, b, c and 2 more").
inline std::string NamedPeers(const std::vector<std::string>& peers) {
  constexpr size_t kMaxNamed = 3;
  std::string named;
  for (size_t i = 0; i < peers.size() && i < kMaxNamed; ++i) named += (i == 0 ? "" : ", ") + peers[i];
  if (peers.size() > kMaxNamed) named += " and " + std::to_string(peers.size() - kMaxNamed) + " more";
  return named;
}

class HandshakeWatchdog {
 public:
  /// Who starves, for the log line: a service (no progress of its own), or an observer (it
  /// hears nothing from the stalled peers).
  enum class Starving { kService, kObserver };

  explicit HandshakeWatchdog(Starving starving = Starving::kService) : starving_(starving) {}

  /// A pending handshake, and no progress, for this long. A handshake that works ends in 15-60 ms
  /// on loopback, about 1 s when Fast DDS resends its first message (a participant that was just
  /// made); one that stalled never ends.
  static constexpr int64_t kStallNs = 4'000'000'000;
  static constexpr int64_t kCheckPeriodNs = 1'000'000'000;    ///< Due() at most this often
  static constexpr int64_t kFirstBackoffNs = 30'000'000'000;  ///< after a reload, the next one at the earliest
  static constexpr int64_t kMaxBackoffNs = 600'000'000'000;

  /// Whether to look now (true at most every kCheckPeriodNs of `now_ns`, monotonic).
  bool Due(int64_t now_ns) {
    if (now_ns < next_check_ns_) return false;
    next_check_ns_ = now_ns + kCheckPeriodNs;
    return true;
  }

  /// `stalled`: the peers whose handshakes have been pending for kStallNs or longer;
  /// `progress_ns`: when the service last made progress (its start, if never). Why the service
  /// should make its participant again now (recorded as a reload: the back-off starts), or
  /// empty.
  std::string Judge(int64_t now_ns, int64_t progress_ns, const std::vector<std::string>& stalled) {
    if (now_ns - progress_ns < kStallNs) {
      // Working (again): a later stall is healed as soon as the first was.
      backoff_ns_ = kFirstBackoffNs;
      not_before_ns_ = 0;
      return {};
    }
    if (stalled.empty() || now_ns < not_before_ns_) return {};
    const std::string peers = NamedPeers(stalled);
    ++reloads_;
    not_before_ns_ = now_ns + backoff_ns_;
    const std::string starved =
        starving_ == Starving::kService
            ? "and this service has made no progress for " + std::to_string((now_ns - progress_ns) / 1'000'000'000) +
                  " s"
            : "so nothing of theirs reaches this command";
    std::string why = "the security handshake with " + peers + " has had no outcome for " +
                      std::to_string(kStallNs / 1'000'000'000) + " s or more, " + starved +
                      " (a Fast DDS 2.9 handshake stall, or a peer that never answers): a new participant, "
                      "handshaken afresh; while nothing improves, the next such reload not before " +
                      std::to_string(backoff_ns_ / 1'000'000'000) + " s";
    backoff_ns_ = std::min(2 * backoff_ns_, kMaxBackoffNs);
    return why;
  }

  /// `returning`: the peers that came back after their lease expired and whose handshakes have
  /// been pending for kStallNs or longer (BusParticipant::PendingHandshakes). Why the service
  /// should make its participant again now, whether or not it works, or empty.
  std::string JudgeReturning(int64_t now_ns, const std::vector<std::string>& returning) {
    if (returning.empty() || now_ns < returning_not_before_ns_) return {};
    ++reloads_;
    returning_not_before_ns_ = now_ns + kFirstBackoffNs;
    return "the security handshake with " + NamedPeers(returning) + ", back after its lease had expired, has had no " +
           "outcome for " + std::to_string(kStallNs / 1'000'000'000) +
           " s or more (Fast DDS 2.9 does not handshake a returning participant again: it would never hear from "
           "this one): a new participant, handshaken afresh";
  }

  /// How many reloads Judge and JudgeReturning asked for.
  uint64_t reloads() const { return reloads_; }

 private:
  Starving starving_;
  int64_t next_check_ns_ = 0;
  int64_t not_before_ns_ = 0;
  int64_t backoff_ns_ = kFirstBackoffNs;
  int64_t returning_not_before_ns_ = 0;  ///< JudgeReturning
  uint64_t reloads_ = 0;
};

}  // namespace dpc::bus
