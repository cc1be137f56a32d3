#pragma once
// A service's DDS participant, made from its options at start and made again on SIGHUP
// (services/common/service.h, Service::RequestReload): DDS Security credentials rotated by
// make-bench-pki.sh (new keys, certificates, grants, the revocation list) take effect without a
// restart, since Fast DDS 2.9 reads them only when a participant is created.
//
// A reload (Reload) makes the new participant first, while the old one still runs: credentials
// or profiles that do not give a participant (a tampered grant, a missing key, a broken profile)
// are refused and the service keeps running on the participant it has. With DDS Security the
// service then keeps running on the old participant while the new one discovers and
// authenticates the peers (about 1 s on loopback): the endpoints move only once the new
// participant has authenticated every peer the old one had (PeersNotYetAuthenticated). A new
// participant that has not done so within kMaxPrepareNs has most likely met a stalled handshake
// itself (Fast DDS 2.9, below): it is replaced by another, up to kMaxPrepareAttempts in all, and
// the endpoints move to the last one whatever it has authenticated. Moving them: the service's
// endpoints deleted (readers first: their callbacks end before anything they use goes), the old
// participant replaced, and the endpoints made again on the new one, whose handshakes are done:
// only the endpoints' own discovery remains.
//
// A secured service also reloads by itself when a peer's handshake has stalled and the service
// starves for it (HandshakeStalled, HandshakeWatchdog).

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dpc/bench/clock.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/handshake_watchdog.h"

namespace dpc::bus {

/// Of the peers `running` has authenticated (GUID prefixes, BusParticipant::AuthenticatedPeers),
/// other than `fresh_self` (the new participant: the old one authenticates it too), how many
/// `fresh` has not authenticated yet; their count in `peers`. A reload moves the endpoints when
/// this is 0. `names`, if given: those peers.
inline size_t PeersNotYetAuthenticated(const std::vector<std::string>& running, const std::vector<std::string>& fresh,
                                       const std::string& fresh_self, size_t* peers,
                                       std::vector<std::string>* names = nullptr) {
  size_t missing = 0;
  *peers = 0;
  for (const std::string& peer : running) {
    if (peer == fresh_self) continue;
    ++*peers;
    if (std::find(fresh.begin(), fresh.end(), peer) != fresh.end()) continue;
    ++missing;
    if (names != nullptr) names->push_back(peer);
  }
  return missing;
}

class ParticipantMaker {
 public:
  /// A line for the service's log: an error, or information.
  using Log = std::function<void(bool error, const std::string& text)>;

  /// `starving`: whose starvation the handshake watchdog reports (HandshakeWatchdog).
  ParticipantMaker(BusOptions options, std::function<void(const PeerEvent&)> on_peer, Log log,
                   HandshakeWatchdog::Starving starving = HandshakeWatchdog::Starving::kService)
      : options_(std::move(options)), on_peer_(std::move(on_peer)), log_(std::move(log)), watchdog_(starving) {}

  /// What a loop guard (cli::LoopGuard::Phase) is told while Reload runs: the phase to name
  /// (kReloadPhase) in, what it returned back. Reload makes and deletes participants and
  /// endpoints, the calls of Fast DDS 2.9 that were seen to deadlock (ARCHITECTURE.md).
  using PhaseReport = std::function<const char*(const char*)>;
  static constexpr const char* kReloadPhase = "a reload of its DDS participant";
  void SetPhaseReport(PhaseReport report) { phase_report_ = std::move(report); }

  /// At start: throws as BusParticipant does (the service cannot start).
  std::unique_ptr<BusParticipant> Make() const { return std::make_unique<BusParticipant>(options_, on_peer_); }

  static constexpr int64_t kMaxPrepareNs = 3'000'000'000;  ///< for one new participant to authenticate the peers
  static constexpr int kMaxPrepareAttempts = 3;              ///< new participants per reload, at most
  static constexpr int64_t kPrepareCheckNs = 5'000'000;     ///< looks at the handshakes at most this often

  /// A reload, from the service's loop, on the thread that owns `*participant` (no reader's
  /// callback may use it while it is replaced: `delete_endpoints` deletes the readers first).
  /// `cause` (what the log lines say, "reload (SIGHUP): …") asks for one now: a new participant;
  /// if it cannot be made, the error is logged and nothing changes. An empty `cause` goes on
  /// with the reload being prepared (call it so while preparing()). Open, the endpoints move at
  /// once; with DDS Security once the new participant has authenticated the old one's peers (a
  /// new participant that has not after kMaxPrepareNs is replaced by another, and the endpoints
  /// move to the kMaxPrepareAttempts-th in any case): `delete_endpoints`, the old participant
  /// replaced by the new one, `make_endpoints` (on it). True when the endpoints moved.
  bool Reload(std::unique_ptr<BusParticipant>* participant, const std::function<void()>& delete_endpoints,
              const std::function<void()>& make_endpoints, const std::string& cause) {
    const PhaseScope phase(phase_report_);
    const int64_t now_ns = MonotonicNs();
    if (!cause.empty()) {
      const std::string credentials =
          options_.security.enabled()
              ? "identity " + options_.security.identity + " of " + options_.security.directory
              : std::string("no DDS Security");
      try {
        fresh_ = Make();  // a reload being prepared is replaced (credentials changed again)
      } catch (const std::exception& e) {
        log_(true, "reload (" + cause + ") refused, the running participant is kept: " + e.what() + " (" +
                       credentials + ")");
        return false;
      }
      cause_ = cause;
      prepared_since_ns_ = now_ns;
      reload_since_ns_ = now_ns;
      attempt_ = 1;
      next_check_ns_ = 0;
      log_(false, "reload (" + cause + "): a new participant (" + credentials + "); " +
                      (fresh_->secure() ? "the endpoints move to it once it has authenticated the peers of the "
                                          "running one (at most " + std::to_string(kMaxPrepareNs / 1'000'000'000) +
                                          " s)"
                                        : "its endpoints follow"));
    }
    if (fresh_ == nullptr) return false;
    std::string how;
    if (fresh_->secure()) {
      if (now_ns < next_check_ns_) return false;
      next_check_ns_ = now_ns + kPrepareCheckNs;
      size_t peers = 0;
      std::vector<std::string> not_yet;
      const size_t missing = PeersNotYetAuthenticated((*participant)->AuthenticatedPeers(),
                                                      fresh_->AuthenticatedPeers(), fresh_->guid_prefix(), &peers,
                                                      &not_yet);
      if (missing > 0 && now_ns - prepared_since_ns_ < kMaxPrepareNs) return false;
      std::string authenticated = "it authenticated " + std::to_string(peers - missing) + " of the " +
                                  std::to_string(peers) + " peers of the old one";
      if (!not_yet.empty()) authenticated += "; not yet " + NamedPeers(not_yet);
      if (missing > 0 && attempt_ < kMaxPrepareAttempts) {
        // Its handshakes with those peers have most likely stalled: another new participant,
        // while the old one goes on serving.
        try {
          fresh_ = Make();
        } catch (const std::exception& e) {
          log_(true, "reload (" + cause_ + "): another new participant could not be made (" + e.what() +
                         "): the endpoints move to the one there is");
          attempt_ = kMaxPrepareAttempts;
          return false;
        }
        ++attempt_;
        prepared_since_ns_ = now_ns;
        log_(false, "reload (" + cause_ + "): the new participant did not authenticate the old one's peers in " +
                        std::to_string(kMaxPrepareNs / 1'000'000'000) + " s (" + authenticated +
                        "): another new participant (" + std::to_string(attempt_) + " of at most " +
                        std::to_string(kMaxPrepareAttempts) + ")");
        return false;
      }
      how = " (after " + std::to_string((now_ns - reload_since_ns_) / 1'000'000) + " ms" +
            (attempt_ > 1 ? " and " + std::to_string(attempt_) + " new participants" : std::string()) + ": " +
            authenticated + ")";
    }
    delete_endpoints();
    *participant = std::move(fresh_);  // the old participant goes
    make_endpoints();
    log_(false, "reload (" + cause_ + "): the endpoints are on the new participant" + how);
    return true;
  }

  /// Whether a reload is being prepared: call Reload with an empty cause until it returns true.
  bool preparing() const { return fresh_ != nullptr; }

  /// What a service's loop asks each turn: a reload to begin ("SIGHUP" if `sighup`, "handshake
  /// stall" if HandshakeStalled), one being prepared to go on with (""), or nothing to do
  /// (nullopt). The cause goes to Reload.
  std::optional<std::string> ReloadCause(bool sighup, const BusParticipant& participant, int64_t now_ns,
                                         int64_t progress_ns) {
    if (sighup) return "SIGHUP";
    if (HandshakeStalled(participant, now_ns, progress_ns)) return "handshake stall";
    if (preparing()) return "";
    return std::nullopt;
  }

  /// As often as convenient (it looks at most once a second; cheap otherwise): with DDS
  /// Security, whether a peer's handshake has had no outcome for HandshakeWatchdog::kStallNs
  /// while the service made no progress since `progress_ns` (monotonic, like `now_ns`) for as
  /// long, or a peer back after its lease expired has had none for as long (JudgeReturning). If
  /// so, a line in the log says so, and the service should Reload(…, "handshake stall") now
  /// (HandshakeWatchdog's back-off is running).
  bool HandshakeStalled(const BusParticipant& participant, int64_t now_ns, int64_t progress_ns) {
    if (!participant.secure() || preparing() || !watchdog_.Due(now_ns)) return false;
    std::string why = watchdog_.JudgeReturning(
        now_ns, participant.PendingHandshakes(HandshakeWatchdog::kStallNs, BusParticipant::kReturningOnly));
    if (why.empty()) {
      why = watchdog_.Judge(now_ns, progress_ns, participant.PendingHandshakes(HandshakeWatchdog::kStallNs));
    }
    if (why.empty()) return false;
    log_(true, why);
    return true;
  }

 private:
  /// kReloadPhase while alive, then the phase before it.
  class PhaseScope {
   public:
    explicit PhaseScope(const PhaseReport& report)
        : report_(report), before_(report ? report(kReloadPhase) : nullptr) {}
    ~PhaseScope() {
      if (report_ && before_ != nullptr) report_(before_);
    }
    PhaseScope(const PhaseScope&) = delete;
    PhaseScope& operator=(const PhaseScope&) = delete;

   private:
    const PhaseReport& report_;
    const char* before_;
  };

  BusOptions options_;
  PhaseReport phase_report_;
  std::function<void(const PeerEvent&)> on_peer_;
  Log log_;
  HandshakeWatchdog watchdog_;
  std::unique_ptr<BusParticipant> fresh_;  ///< a reload being prepared
  std::string cause_;
  int64_t prepared_since_ns_ = 0;  ///< when fresh_ was made
  int64_t reload_since_ns_ = 0;    ///< when the reload was asked for
  int attempt_ = 0;                ///< fresh_ is the reload's attempt_-th new participant
  int64_t next_check_ns_ = 0;
};

}  // namespace dpc::bus
