#!/usr/bin/env bash
# The solver on another "host": the bench (dpc-polarimeter + dpc-driver) in network namespace A,
# the controller in namespace B, joined only by a veth pair (10.99.X.1/24 ↔ 10.99.X.2/24).
# Every participant uses UDPv4 whitelisted to its namespace's veth address, built-in transports
# off (no SHM, nothing else); the namespaces have no route to any other network, so no DDS
# traffic can leave them.
#
#   netns_bench_test.sh CASE DPC_DRIVER DPC_CONTROLLER DPC_POLARIMETER LOOPBACK_XML [DPC]
#
# CASE peers:  discovery by unicast only: initial peers = both veth addresses, metatraffic
#              unicast locators on the veth address, no multicast locators.
# CASE server: a Fast DDS discovery server (fast-discovery-server -x) bound to A's veth address;
#              every service is a CLIENT of it (no multicast, no initial peers).
# CASE secure_peers: peers, with DDS Security (Fast DDS 2.9 has no secure discovery server):
#              a bench PKI made by deploy/security/make-bench-pki.sh for this domain, every
#              service with --security-dir (its role's identity); afterwards a participant of B
#              without credentials must see nothing of the bench.
# CASE peers_cut, secure_peers_cut: peers (open or secured), and once the driver has obeyed the
#              controller for 2 s, the link is cut for CUT_S (DPC_NETNS_CUT_S, default 10 s: twice
#              the profiles' 5-s lease, so each side drops the other) and restored. Asserts that
#              the driver holds within 1 s of the cut, obeys the controller again for 2 s without
#              a hold within RELOCK_LIMIT_S (20 s) of the link's return, and that the loop is
#              locked at the end; prints both times. Secured, peers must authenticate each other
#              again; a cut a little shorter than the lease leaves one side still trusting the
#              other, and the side that dropped it waits for a handshake that Fast DDS 2.9 never
#              starts, until bus::HandshakeWatchdog makes its participant again (about 5 s).
# Asserts from the polarimeter's JSON summary (real time, 2 kHz, 6 s; cut cases: until stopped) that the loop locked
# (first_lock_time_s), the median error after lock is below 2° (secure: 3°) and the mean below 10° (see below); prints the time the
# controller needed to receive the device description across the namespaces (discovery +
# TRANSIENT_LOCAL delivery). DPC_NETNS_RATE_HZ overrides the polarimeter's rate (2000).
#
# Needs root and `ip netns` (exit 77 = skipped otherwise). Cleans up its processes and
# namespaces on any exit; DPC_NETNS_KEEP_LOGS=DIR keeps the profiles and logs there.
set -euo pipefail

if [[ $# -ne 5 && $# -ne 6 ]]; then
  echo "usage: $0 peers|server|secure_peers|peers_cut|secure_peers_cut" \
    "DPC_DRIVER DPC_CONTROLLER DPC_POLARIMETER LOOPBACK_XML [DPC]" >&2
  exit 2
fi
CASE=$1
DRIVER=$2
CONTROLLER=$3
POLARIMETER=$4
LOOPBACK_XML=$5
DPC=${6:-}  # the dpc tool: the cut cases watch the driver's states with it
case $CASE in peers|server|secure_peers|peers_cut|secure_peers_cut) ;; *) echo "unknown case $CASE" >&2; exit 2 ;; esac
# BASE: the deployment (peers, server, secure_peers); CUT: whether the link is cut during the run.
BASE=${CASE%_cut}
CUT=0
[[ $CASE == *_cut ]] && CUT=1

skip() { echo "SKIP: $*"; exit 77; }
[[ $(id -u) -eq 0 ]] || skip "needs root (network namespaces)"
command -v ip >/dev/null || skip "ip (iproute2) not installed"
command -v jq >/dev/null || skip "jq not installed"
command -v ss >/dev/null || skip "ss (iproute2) not installed"
if [[ $CASE == server ]]; then
  command -v fast-discovery-server >/dev/null || skip "fast-discovery-server (fastdds-tools) not installed"
fi
TOOLS=("$DRIVER" "$CONTROLLER" "$POLARIMETER")
(( CUT )) && TOOLS+=("$DPC")
for f in "${TOOLS[@]}"; do
  [[ -x $f ]] || { echo "FAIL: $f is not built" >&2; exit 1; }
done

NS_A="dpcA-$$"
NS_B="dpcB-$$"
VETH_A="dva$$"           # ≤ 15 characters for any PID
VETH_B="dvb$$"
X=$(( $$ % 250 + 1 ))
ADDR_A="10.99.$X.1"
ADDR_B="10.99.$X.2"
DOMAIN=62
RATE_HZ=${DPC_NETNS_RATE_HZ:-2000}
# Secured, the three services take ~150 % of this 2-core machine's CPU at 2 kHz (every message
# signed and encrypted): a busy neighbour then costs the loop tens of degrees. 1 kHz leaves room.
[[ $BASE == secure_peers ]] && RATE_HZ=${DPC_NETNS_RATE_HZ:-1000}
[[ $CASE == server ]] && DOMAIN=63
[[ $CASE == secure_peers ]] && DOMAIN=60
[[ $CASE == peers_cut ]] && DOMAIN=71
[[ $CASE == secure_peers_cut ]] && DOMAIN=61
CUT_S=${DPC_NETNS_CUT_S:-10}
RELOCK_LIMIT_S=20
SERVER_PORT=11811
WORK=$(mktemp -d /tmp/dpc-netns.XXXXXX)
PIDS=()
NAMESPACES=()

cleanup() {
  local rc=$?
  set +e
  for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2>/dev/null; done
  for pid in "${PIDS[@]}"; do
    for _ in $(seq 30); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null
  done
  for ns in "${NAMESPACES[@]}"; do ip netns del "$ns" 2>/dev/null; done
  if [[ $rc -ne 0 && $rc -ne 77 ]]; then
    for log in "$WORK"/*.log "$WORK"/*.json; do
      [[ -f $log ]] && { echo "--- $(basename "$log")"; tail -n 40 "$log"; }
    done
  fi
  if [[ -n ${DPC_NETNS_KEEP_LOGS:-} ]]; then
    mkdir -p "$DPC_NETNS_KEEP_LOGS" && cp -r "$WORK"/. "$DPC_NETNS_KEEP_LOGS"/
  fi
  rm -rf "$WORK"
  exit $rc
}
trap cleanup EXIT
trap 'exit 1' INT TERM

fail() { echo "FAIL: $*" >&2; exit 1; }

# --- namespaces --------------------------------------------------------------------------------
ip netns add "$NS_A" 2>/dev/null || skip "cannot create network namespaces (ip netns add failed)"
NAMESPACES+=("$NS_A")
ip netns add "$NS_B" || fail "ip netns add $NS_B"
NAMESPACES+=("$NS_B")
# The veth pair is created directly inside the two namespaces: it never appears on the host.
ip link add "$VETH_A" netns "$NS_A" type veth peer name "$VETH_B" netns "$NS_B"
ip -n "$NS_A" addr add "$ADDR_A/24" dev "$VETH_A"
ip -n "$NS_B" addr add "$ADDR_B/24" dev "$VETH_B"
for ns in "$NS_A" "$NS_B"; do ip -n "$ns" link set lo up; done
ip -n "$NS_A" link set "$VETH_A" up
ip -n "$NS_B" link set "$VETH_B" up
veth_up() {
  ip -n "$NS_A" -o link show "$VETH_A" | grep -q 'state UP' &&
    ip -n "$NS_B" -o link show "$VETH_B" | grep -q 'state UP'
}
for _ in $(seq 100); do veth_up && break; sleep 0.05; done
veth_up || fail "the veth pair $VETH_A/$VETH_B did not come up"
echo "namespaces $NS_A ($ADDR_A) and $NS_B ($ADDR_B), case $CASE, domain $DOMAIN"

# --- Fast DDS profiles (deploy/fastdds/make_profile.sh, next to the loopback file) --------------
# The topic profiles ("<topic>.writer/.reader") are copied from the loopback file, so the QoS is
# the bench's; only the transport (UDPv4 on the veth address) and discovery differ.
MAKE_PROFILE="$(dirname "$LOOPBACK_XML")/make_profile.sh"
[[ -x $MAKE_PROFILE ]] || fail "$MAKE_PROFILE missing"
if [[ $BASE == peers || $BASE == secure_peers ]]; then
  "$MAKE_PROFILE" --topics-from "$LOOPBACK_XML" --address "$ADDR_A" --peers "$ADDR_B" >"$WORK/profile_a.xml"
  "$MAKE_PROFILE" --topics-from "$LOOPBACK_XML" --address "$ADDR_B" --peers "$ADDR_A" >"$WORK/profile_b.xml"
else
  for side in a b; do
    addr=$ADDR_A; [[ $side == b ]] && addr=$ADDR_B
    "$MAKE_PROFILE" --topics-from "$LOOPBACK_XML" --address "$addr" --server "$ADDR_A:$SERVER_PORT" \
      >"$WORK/profile_$side.xml"
  done
  "$MAKE_PROFILE" --discovery-server "$ADDR_A:$SERVER_PORT" >"$WORK/server.xml"
fi
topic_profiles=$(grep -c 'profile_name="dpc_' "$LOOPBACK_XML")  # a writer and a reader per topic
for f in "$WORK"/profile_[ab].xml; do
  [[ $(grep -c 'profile_name="dpc_' "$f") -eq $topic_profiles ]] ||
    fail "expected the $topic_profiles topic profiles of $LOOPBACK_XML in $f"
  # No multicast anywhere: discovery must not depend on it.
  ! grep -q -i multicast "$f" || fail "$f mentions multicast"
done

# --- DDS Security (case secure_peers) -----------------------------------------------------------
SECURITY=()
if [[ $BASE == secure_peers ]]; then
  PKI_SCRIPT="$(dirname "$LOOPBACK_XML")/../security/make-bench-pki.sh"
  "$PKI_SCRIPT" --out "$WORK/pki" --bench bench1 --controllers remote --domains "$DOMAIN" 2>"$WORK/pki.log" ||
    fail "make-bench-pki.sh failed: $(tail -n 5 "$WORK/pki.log")"
  SECURITY=(--security-dir "$WORK/pki")
fi

# run_in NS PROFILE LOG CMD...: a service in a namespace, in the background; its PID is recorded.
run_in() {
  local ns=$1 profile=$2 log=$3
  shift 3
  ip netns exec "$ns" env FASTRTPS_DEFAULT_PROFILES_FILE="$profile" "$@" >"$log" 2>&1 &
  PIDS+=($!)
}

# wait_for SECONDS DESCRIPTION COMMAND...: polls every 20 ms.
wait_for() {
  local limit=$1 what=$2
  shift 2
  local end=$(( $(date +%s%N) + limit * 1000000000 ))
  until "$@" >/dev/null 2>&1; do
    (( $(date +%s%N) < end )) || fail "timed out after ${limit} s waiting for $what"
    sleep 0.02
  done
}

# wait_for_quietly SECONDS COMMAND...: as wait_for, but returns 1 on time-out instead of failing.
wait_for_quietly() {
  local limit=$1
  shift
  local end=$(( $(date +%s%N) + limit * 1000000000 ))
  until "$@" >/dev/null 2>&1; do
    (( $(date +%s%N) < end )) || return 1
    sleep 0.02
  done
}

# --- discovery server (case server) ------------------------------------------------------------
if [[ $CASE == server ]]; then
  t0=$(date +%s%N)
  ip netns exec "$NS_A" fast-discovery-server -x "$WORK/server.xml" >"$WORK/server.log" 2>&1 &
  PIDS+=($!)
  server_listening() {
    ip netns exec "$NS_A" ss -Hunl "src $ADDR_A:$SERVER_PORT" | grep -q .
  }
  wait_for 20 "the discovery server on $ADDR_A:$SERVER_PORT" server_listening
  echo "discovery server listening on $ADDR_A:$SERVER_PORT after $(( ($(date +%s%N) - t0) / 1000000 )) ms"
  # Nothing but the veth address (fast-discovery-server -l would bind 0.0.0.0).
  if ip netns exec "$NS_A" ss -Hunlp | awk '/fast-discovery/ { print $4 }' | grep -q -v "^$ADDR_A:"; then
    fail "the discovery server bound another address than $ADDR_A: $(ip netns exec "$NS_A" ss -Hunlp | grep fast-discovery)"
  fi
fi

# --- the bench: driver in A, controller in B, then the polarimeter in A ------------------------
run_in "$NS_A" "$WORK/profile_a.xml" "$WORK/driver.log" "$DRIVER" --domain "$DOMAIN" --device-record "$WORK/driver.record" "${SECURITY[@]}"
t0=$(date +%s%N)
run_controller() {
  run_in "$NS_B" "$WORK/profile_b.xml" "$WORK/controller.log" "$CONTROLLER" --domain "$DOMAIN" --id remote "${SECURITY[@]}"
  CONTROLLER_PID=$!
}
run_controller
# forget_pid PID: a service replaced on purpose (not "exited early").
forget_pid() {
  local kept=() pid
  for pid in "${PIDS[@]}"; do [[ $pid == "$1" ]] || kept+=("$pid"); done
  PIDS=("${kept[@]}")
}
# authenticated_by_driver NAME: the driver's log says its security handshake with NAME finished.
authenticated_by_driver() { grep -q "participant authenticated: .*($1)" "$WORK/driver.log"; }
if [[ $BASE == secure_peers ]]; then
  # Fast DDS 2.9: the handshake of two participants can stall for good (both discovered, neither
  # ever authenticated; see ARCHITECTURE.md). The starved controller makes its participant again
  # by itself after about 4 s (bus::HandshakeWatchdog); should that not be enough, a restart is
  # done once here, at 15 s, and said; a second stall fails.
  if ! wait_for_quietly 15 grep -q "device: 3 stages" "$WORK/controller.log" &&
     ! authenticated_by_driver dpc-controller/remote; then
    echo "note: the driver's security handshake with the controller did not finish in 15 s (a Fast DDS 2.9 stall); restarting the controller once"
    kill -TERM "$CONTROLLER_PID" 2>/dev/null || true
    wait "$CONTROLLER_PID" || true
    forget_pid "$CONTROLLER_PID"
    mv "$WORK/controller.log" "$WORK/controller-stalled.log"
    run_controller
  fi
fi
wait_for 30 "the controller (namespace B) to receive the device description from the driver (A)" \
  grep -q "device: 3 stages" "$WORK/controller.log"
discovery_ms=$(( ($(date +%s%N) - t0) / 1000000 ))
echo "controller in $NS_B received the device description after $discovery_ms ms"

# For the record: the UDP sockets of the services (namespaces hold only lo and the veth).
for ns in "$NS_A" "$NS_B"; do
  echo "UDP sockets in $ns: $(ip netns exec "$ns" ss -Hunl | awk '{ print $4 }' | sort -u | tr '\n' ' ')"
done

if [[ $BASE == secure_peers ]]; then
  # A controller in B without credentials, for the whole run: never matched, it learns nothing.
  run_in "$NS_B" "$WORK/profile_b.xml" "$WORK/intruder.log" "$CONTROLLER" --domain "$DOMAIN" --id intruder --priority 100
fi

RUN_S=6
(( CUT )) && RUN_S=0  # until stopped, once the cut is over
run_polarimeter() {
  ip netns exec "$NS_A" env FASTRTPS_DEFAULT_PROFILES_FILE="$WORK/profile_a.xml" \
    "$POLARIMETER" --domain "$DOMAIN" --rate-hz "$RATE_HZ" --run-s "$RUN_S" --json "${SECURITY[@]}" \
    >"$WORK/polarimeter.json" 2>"$WORK/polarimeter.log" &
  POL_PID=$!
  PIDS+=("$POL_PID")
}
run_polarimeter
if [[ $BASE == secure_peers ]] &&
   ! wait_for_quietly 15 authenticated_by_driver dpc-polarimeter/bench1; then
  # The same stall between the polarimeter and the driver: the driver would never see a sample
  # (the polarimeter's own heal comes after 4 s, too late for most of this 6-s run).
  echo "note: the driver's security handshake with the polarimeter did not finish in 15 s (a Fast DDS 2.9 stall); restarting the polarimeter once"
  kill -TERM "$POL_PID" 2>/dev/null || true
  wait "$POL_PID" || true
  forget_pid "$POL_PID"
  mv "$WORK/polarimeter.log" "$WORK/polarimeter-stalled.log"
  run_polarimeter
fi

# --- the cut (cases *_cut) ----------------------------------------------------------------------
# The driver's states, as `dpc topic echo` in A prints them (secured: the observer identity), say
# when it held and when it obeyed again: each carries its mode and its publish time (the wall
# clock, which the namespaces share with this script).
now_ns() { date +%s%N; }
# states_ms SINCE_NS MODE HOLD_MS: ms from SINCE_NS to the first state of MODE published after it
# that begins HOLD_MS of states of that mode only; nothing if there is none yet. Reads the states
# from byte STATES_FROM on (its first line, maybe cut, is skipped; so is a half-written last).
STATES_FROM=0
states_ms() {
  tail -c +$(( STATES_FROM + 1 )) "$WORK/states.jsonl" 2>/dev/null | tail -n +2 |
    awk -v since="$1" -v mode="\"mode\":\"$2\"" -v hold_ns="$(( $3 * 1000000 ))" '
      !match($0, /"publish_time_ns":[0-9]+/) { next }
      { t = substr($0, RSTART + 18, RLENGTH - 18) + 0 }
      t < since { next }
      index($0, mode) {
        if (start == "") start = t
        if (t - start >= hold_ns) { printf "%d\n", (start - since) / 1e6; exit }
        next
      }
      { start = "" }' || true  # awk's early exit ends the readers before it (SIGPIPE)
}
states_reached() { [[ -n $(states_ms "$@") ]]; }
if (( CUT )); then
  run_in "$NS_A" "$WORK/profile_a.xml" "$WORK/echo.log" bash -c \
    'exec "$0" topic echo dpc_waveplate_state --domain "$1" --json "${@:3}" >"$2"' \
    "$DPC" "$DOMAIN" "$WORK/states.jsonl" "${SECURITY[@]}"
  wait_for 30 "the driver to obey the controller for 2 s before the cut (its states, seen by dpc topic echo)" \
    states_reached 0 DRIVER_ACTIVE 2000
  STATES_FROM=$(stat -c %s "$WORK/states.jsonl")
  t_cut=$(now_ns)
  ip -n "$NS_B" link set "$VETH_B" down
  echo "link cut for $CUT_S s (the lease is 5 s)"
  wait_for 2 "the driver to hold once the link was cut" states_reached "$t_cut" DRIVER_HOLDING 0
  sleep "$(awk -v cut="$CUT_S" -v since="$t_cut" -v now="$(now_ns)" 'BEGIN { print cut - (now - since) / 1e9 }')"
  ip -n "$NS_A" link set "$VETH_A" up
  ip -n "$NS_B" link set "$VETH_B" up
  for _ in $(seq 100); do veth_up && break; sleep 0.05; done
  veth_up || fail "the veth pair did not come up again"
  t_up=$(now_ns)
  echo "link restored after $(( (t_up - t_cut) / 1000000 )) ms"
  # Obeyed again: 2 s of active states without a hold (a command or two that crossed while a
  # peer was not yet authenticated again is not a recovery).
  wait_for "$RELOCK_LIMIT_S" "the driver to obey the controller for 2 s after the link came back" \
    states_reached "$t_up" DRIVER_ACTIVE 2000
  # What the services did meanwhile (reloads of the security watchdog, re-authentication).
  for log in driver controller polarimeter; do
    grep -h -E "lease had expired|has had no outcome|participant again|participant authenticated" \
      "$WORK/$log.log" 2>/dev/null | tail -n 4 | cut -c1-200 | sed "s/^/  $log: /" || true
  done
  sleep 2  # locked operation to the end
  kill -TERM "$POL_PID" 2>/dev/null || true
  hold_ms=$(states_ms "$t_cut" DRIVER_HOLDING 0)
  again_ms=$(states_ms "$t_up" DRIVER_ACTIVE 2000)
  echo "the driver held ${hold_ms} ms after the cut and obeyed the controller again" \
    "${again_ms} ms after the link came back"
  (( hold_ms <= 1000 )) || fail "the driver held only ${hold_ms} ms after the cut (limit 1000 ms)"
fi
wait "$POL_PID" || fail "dpc-polarimeter failed"
SUMMARY=$(grep '^{' "$WORK/polarimeter.json" | tail -n 1)
[[ -n $SUMMARY ]] || fail "no JSON summary from dpc-polarimeter"
for pid in "${PIDS[@]}"; do
  [[ $pid == "$POL_PID" ]] && continue
  kill -0 "$pid" 2>/dev/null || fail "a service (PID $pid) exited early"
done

if [[ $BASE == secure_peers ]]; then
  ! grep -q "device:" "$WORK/intruder.log" || fail "a controller without credentials got the device description"
  grep -q "waiting for the device description" "$WORK/intruder.log" ||
    fail "the controller without credentials did not run: $(tail -n 5 "$WORK/intruder.log")"
  echo "a controller without credentials in $NS_B saw nothing of the secure bench during the run"
fi

echo "$SUMMARY" | jq -c '{lock_time_s, first_lock_time_s, error_deg, bench: .bench}'
# lock_time_s: from when the error stays below 10° to the end; unset if the last sample is above.
# A process starved at the very end would unset it, so the hard check is the first lock plus the
# median below; a missing lock_time_s is reported.
echo "$SUMMARY" | jq -e '.first_lock_time_s != null' >/dev/null || fail "the loop never locked across the namespaces"
if (( CUT )); then
  # The statistics cover the cut, when the error wanders with the scrambler: what counts is that
  # the loop locked again and stayed locked to the end (4 s after the driver obeyed again).
  echo "$SUMMARY" | jq -e '.lock_time_s != null' >/dev/null ||
    fail "the loop was not locked at the end, after the link came back:" \
      "$(echo "$SUMMARY" | jq -c '{lock_time_s, error_deg}')"
  printf 'PASS (%s): held %d ms after the cut; obeyed again %d ms after the link came back (cut %s s, lease 5 s); locked from %s s to the end\n' \
    "$CASE" "$hold_ms" "$again_ms" "$CUT_S" "$(echo "$SUMMARY" | jq '.lock_time_s*1000|round/1000')"
  exit 0
fi
if ! echo "$SUMMARY" | jq -e '.lock_time_s != null' >/dev/null; then
  echo "note: the error was above 10° at the end of the run (lock_time_s null)"
fi
# While locked the error is ~1.2° at 2 kHz (20 rad/s scrambler × ~1 ms loop). The median must be
# below 2°: the loop holds the target most of the time. The mean is bounded loosely (10°): on this
# shared 2-core machine a process starved for 100 ms lets the scrambler move the light by 2 rad,
# which adds a few degrees to the mean without anything wrong on the network.
# Secured, at 1 kHz (above), every message signed and encrypted: locked, the error is ~2.4°
# (median 2.3-2.5° in runs on this machine, p99 4-4.6°); its median bound is 4°.
P50_LIMIT_DEG=2
MEAN_NOTE_DEG=2
[[ $BASE == secure_peers ]] && { P50_LIMIT_DEG=4; MEAN_NOTE_DEG=3.5; }
echo "$SUMMARY" | jq -e --argjson limit "$P50_LIMIT_DEG" '.error_deg.p50 != null and .error_deg.p50 < $limit' >/dev/null ||
  fail "median error after lock is not below ${P50_LIMIT_DEG}°: $(echo "$SUMMARY" | jq -c .error_deg)"
echo "$SUMMARY" | jq -e '.error_deg.mean != null and .error_deg.mean < 10' >/dev/null ||
  fail "mean error after lock is not below 10°: $(echo "$SUMMARY" | jq -c .error_deg)"
if ! echo "$SUMMARY" | jq -e --argjson note "$MEAN_NOTE_DEG" '.error_deg.mean < $note' >/dev/null; then
  echo "note: mean error $(echo "$SUMMARY" | jq .error_deg.mean)° ≥ ${MEAN_NOTE_DEG}°: the loop lost the target for a while (CPU starvation?)"
fi
echo "$SUMMARY" | jq -e --argjson rate "$RATE_HZ" '.bench.published >= 3 * $rate' >/dev/null ||
  fail "the polarimeter published too few samples: $(echo "$SUMMARY" | jq -c .bench)"
printf 'PASS (%s): device description after %d ms; first lock at %s s, locked from %s s; error mean %s° p99 %s°; %s Hz achieved\n' \
  "$CASE" "$discovery_ms" "$(echo "$SUMMARY" | jq '.first_lock_time_s*1000|round/1000')" \
  "$(echo "$SUMMARY" | jq 'if .lock_time_s then .lock_time_s*1000|round/1000 else null end')" \
  "$(echo "$SUMMARY" | jq '.error_deg.mean*1000|round/1000')" \
  "$(echo "$SUMMARY" | jq '.error_deg.p99*1000|round/1000')" \
  "$(echo "$SUMMARY" | jq '.bench.achieved_rate_hz|round')"
