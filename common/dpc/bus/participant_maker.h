#pragma once
// A service's DDS participant, made from its options at start and made again on SIGHUP
// (services/common/service.h, Service::RequestReload): DDS Security credentials rotated by
// make-bench-pki.sh (new keys, certificates, grants, the revocation list) take effect without a
// restart, since Fast DDS 2.9 reads them only when a participant is created.
//
// A reload (Reload) makes the new participant first, while the old one still runs: credentials
// or profiles that do not give a participant (a tampered grant, a missing key, a broken profile)
// are refused and the service keeps running on the participant it has. Only then are the
// service's endpoints deleted (readers first: their callbacks end before anything they use
// goes), the old participant replaced, and the endpoints made again on the new one.
//
// A secured service also reloads by itself when a peer's handshake has stalled and the service
// starves for it (HandshakeStalled, HandshakeWatchdog).

#include <functional>
#include <memory>
#include <string>
#include <utility>

#include "dpc/bus/bus_participant.h"
#include "dpc/bus/handshake_watchdog.h"

namespace dpc::bus {

class ParticipantMaker {
 public:
  /// A line for the service's log: an error, or information.
  using Log = std::function<void(bool error, const std::string& text)>;

  /// `starving`: whose starvation the handshake watchdog reports (HandshakeWatchdog).
  ParticipantMaker(BusOptions options, std::function<void(const PeerEvent&)> on_peer, Log log,
                   HandshakeWatchdog::Starving starving = HandshakeWatchdog::Starving::kService)
      : options_(std::move(options)), on_peer_(std::move(on_peer)), log_(std::move(log)), watchdog_(starving) {}

  /// At start: throws as BusParticipant does (the service cannot start).
  std::unique_ptr<BusParticipant> Make() const { return std::make_unique<BusParticipant>(options_, on_peer_); }

  /// A reload, on the thread that owns `*participant` (no reader's callback may use it while it
  /// is replaced: `delete_endpoints` deletes the readers first). A new participant; if it cannot
  /// be made, the error is logged and nothing changes (false). Else `delete_endpoints`, the old
  /// participant replaced by the new one, `make_endpoints` (on it), and true.
  /// `cause`: what the log lines say ("reload (SIGHUP): …").
  bool Reload(std::unique_ptr<BusParticipant>* participant, const std::function<void()>& delete_endpoints,
              const std::function<void()>& make_endpoints, const std::string& cause = "SIGHUP") const {
    const std::string credentials =
        options_.security.enabled()
            ? "identity " + options_.security.identity + " of " + options_.security.directory
            : std::string("no DDS Security");
    std::unique_ptr<BusParticipant> fresh;
    try {
      fresh = Make();
    } catch (const std::exception& e) {
      log_(true, "reload (" + cause + ") refused, the running participant is kept: " + e.what() + " (" +
                     credentials + ")");
      return false;
    }
    log_(false, "reload (" + cause + "): a new participant (" + credentials + "); its endpoints follow");
    delete_endpoints();
    *participant = std::move(fresh);  // the old participant goes
    make_endpoints();
    log_(false, "reload (" + cause + "): the endpoints are on the new participant");
    return true;
  }

  /// As often as convenient (it looks at most once a second; cheap otherwise): with DDS
  /// Security, whether a peer's handshake has had no outcome for HandshakeWatchdog::kStallNs
  /// while the service made no progress since `progress_ns` (monotonic, like `now_ns`) for as
  /// long. If so, a line in the log says so, and the service should Reload(…, "handshake stall")
  /// now (HandshakeWatchdog's back-off is running).
  bool HandshakeStalled(const BusParticipant& participant, int64_t now_ns, int64_t progress_ns) {
    if (!participant.secure() || !watchdog_.Due(now_ns)) return false;
    const std::string why =
        watchdog_.Judge(now_ns, progress_ns, participant.PendingHandshakes(HandshakeWatchdog::kStallNs));
    if (why.empty()) return false;
    log_(true, why);
    return true;
  }

 private:
  BusOptions options_;
  std::function<void(const PeerEvent&)> on_peer_;
  Log log_;
  HandshakeWatchdog watchdog_;
};

}  // namespace dpc::bus
