#!/usr/bin/env bash
# Cyclone DDS ↔ Fast DDS interop on loopback: dpc-driver (Fast DDS, deploy/fastdds/loopback.xml)
# and dpc-cyclone-probe (Cyclone DDS, built from the same idl/dpc/bench.idl, confined to `lo`).
#
#   cyclone_interop_test.sh DPC_DRIVER CYCLONE_PROBE FASTDDS_PROFILES CYCLONE_CONFIG
#
# 1. Cyclone reads what the driver publishes: the device description of the default scenario
#    (3 fixed-axis stages on [1,0,0], [0,0,1], [1,0,0], linear maps θ = π·φ), the target (revision
#    1, point [0, 0.6, 0.8]) and waveplate states (φ = the scenario's initial φ, exactly).
# 2. Cyclone writes a TargetRequest; the driver accepts it (reply accepted, revision 2) and
#    publishes dpc_target revision 2 (of the driver's epoch) with Cyclone's request id and point, read back by Cyclone.
# Domain 61 (the project's test range is 60–79) and a bench id with this PID keep concurrent
# runs apart.
set -euo pipefail

if [[ $# -ne 4 ]]; then
  echo "usage: $0 DPC_DRIVER CYCLONE_PROBE FASTDDS_PROFILES CYCLONE_CONFIG" >&2
  exit 2
fi
DRIVER=$1
PROBE=$2
FASTDDS_PROFILES=$3
CYCLONE_CONFIG=$4
for f in "$DRIVER" "$PROBE"; do
  [[ -x $f ]] || { echo "FAIL: $f is not built" >&2; exit 1; }
done
command -v jq >/dev/null || { echo "SKIP: jq not installed"; exit 77; }

DOMAIN=61
BENCH="interop-$$"
WORK=$(mktemp -d /tmp/dpc-interop.XXXXXX)
DRIVER_PID=""
cleanup() {
  local rc=$?
  if [[ -n $DRIVER_PID ]] && kill -0 "$DRIVER_PID" 2>/dev/null; then
    kill -TERM "$DRIVER_PID" 2>/dev/null || true
    for _ in $(seq 50); do kill -0 "$DRIVER_PID" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$DRIVER_PID" 2>/dev/null || true
  fi
  if [[ $rc -ne 0 ]]; then
    echo "--- driver log"; cat "$WORK/driver.log" 2>/dev/null || true
    echo "--- probe stderr"; cat "$WORK"/probe*.err 2>/dev/null || true
    echo "--- probe stdout"; cat "$WORK"/probe*.jsonl 2>/dev/null || true
  fi
  rm -rf "$WORK"
  exit $rc
}
trap cleanup EXIT
trap 'exit 1' INT TERM

fail() { echo "FAIL: $*" >&2; exit 1; }

export FASTRTPS_DEFAULT_PROFILES_FILE=$FASTDDS_PROFILES
export CYCLONEDDS_URI="file://$CYCLONE_CONFIG"

# The default bench scenario, with a non-zero initial φ so that the states carry distinctive
# values (binary fractions: exact in decimal JSON too).
SCENARIO="$WORK/scenario.pbtxt"
sed 's/^controller {$/controller {\n  initial_phi: 0.25 initial_phi: -0.5 initial_phi: 0.125/' \
  "$(dirname "$FASTDDS_PROFILES")/../scenarios/bench_default.pbtxt" >"$SCENARIO"
grep -q "initial_phi: 0.25" "$SCENARIO" || fail "could not write the scenario"

"$DRIVER" "$SCENARIO" --domain "$DOMAIN" --bench-id "$BENCH" --device-record "$WORK/waveplates" \
  >"$WORK/driver.log" 2>&1 &
DRIVER_PID=$!

# --- 1. Cyclone reads the Fast DDS topics --------------------------------------------------------
"$PROBE" --domain "$DOMAIN" --bench-id "$BENCH" --states 3 --timeout-s 30 \
  >"$WORK/probe1.jsonl" 2>"$WORK/probe1.err" || fail "the Cyclone probe did not read the topics"
kill -0 "$DRIVER_PID" 2>/dev/null || fail "dpc-driver exited"
cat "$WORK/probe1.err"

J1="$WORK/probe1.jsonl"
jq -e . "$J1" >/dev/null || fail "the probe's output is not JSON lines"

jq -se --arg b "$BENCH" '
  map(select(.topic == "dpc_device_description")) | last |
  .bench_id == $b and .driver_id != "" and
  (.stages | length) == 3 and
  ([.stages[].axis] == [[1,0,0],[0,0,1],[1,0,0]]) and
  ([.stages[].kind] | all(. == "STAGE_FIXED_AXIS")) and
  ([.stages[].map.kind] | all(. == "MAP_LINEAR")) and
  ([.stages[].map.rad_per_unit] | all(. == 3.141592653589793)) and
  ([.stages[].name] == ["wp1","wp2","wp3"])
' "$J1" >/dev/null || fail "device description not intact: $(jq -c 'select(.topic == "dpc_device_description")' "$J1")"
echo "ok: device description (3 stages, axes [1,0,0] [0,0,1] [1,0,0], θ = π·φ) read by Cyclone"

jq -se --arg b "$BENCH" '
  map(select(.topic == "dpc_target")) | last |
  .bench_id == $b and .request_id == "" and .kind == "TARGET_POINT" and .point == [0, 0.6, 0.8]
' "$J1" >/dev/null || fail "target not intact: $(jq -c 'select(.topic == "dpc_target")' "$J1")"
# The revision is epoch << 32 | count: 64 bits, beyond jq's doubles; read from the text.
revision=$(grep '"topic":"dpc_target"' "$J1" | tail -1 | grep -o '"revision":[0-9]*' | cut -d: -f2)
[[ -n "$revision" && $((revision & 0xffffffff)) -eq 1 && $((revision >> 32)) -gt 0 ]] ||
  fail "target revision ${revision:-missing}: not the first of a driver's epoch"
echo "ok: target revision 1 of epoch $((revision >> 32)), point [0, 0.6, 0.8] read by Cyclone"

jq -se --arg b "$BENCH" '
  map(select(.topic == "dpc_waveplate_state")) |
  length >= 3 and all(.bench_id == $b and (.phi_applied | length) == 3 and
                      (.phi_applied == [0.25, -0.5, 0.125]) and (.saturated | length) == 3 and
                      (.mode == "DRIVER_HOLDING" or .mode == "DRIVER_ACTIVE"))
' "$J1" >/dev/null || fail "waveplate states not intact: $(jq -c 'select(.topic == "dpc_waveplate_state")' "$J1")"
echo "ok: $(jq -s 'map(select(.topic == "dpc_waveplate_state")) | length' "$J1") waveplate states with φ = [0.25, -0.5, 0.125] (the scenario's initial φ), e.g. $(jq -c 'select(.topic == "dpc_waveplate_state") | {sequence_number, phi_applied, mode}' "$J1" | head -1)"

# --- 2. Cyclone writes a TargetRequest; the driver acts on it ------------------------------------
REQ="cyclone-$$"
"$PROBE" --domain "$DOMAIN" --bench-id "$BENCH" --states 0 --timeout-s 30 \
  --request 0.6,0.8,0 --request-id "$REQ" \
  >"$WORK/probe2.jsonl" 2>"$WORK/probe2.err" || fail "the driver did not publish the requested target"
kill -0 "$DRIVER_PID" 2>/dev/null || fail "dpc-driver exited"
cat "$WORK/probe2.err"
J2="$WORK/probe2.jsonl"

# Revisions are epoch << 32 | count (64 bits, beyond jq's doubles): compared as text.
epoch=$((revision >> 32))
second=$(((epoch << 32) | 2))
jq -se --arg b "$BENCH" --arg r "$REQ" '
  map(select(.topic == "dpc_target" and .request_id == $r)) | last |
  .bench_id == $b and .kind == "TARGET_POINT" and .point == [0.6, 0.8, 0]
' "$J2" >/dev/null || fail "no target for request $REQ: $(jq -c 'select(.topic == "dpc_target")' "$J2")"
grep '"topic":"dpc_target"' "$J2" | grep "\"request_id\":\"$REQ\"" | grep -q "\"revision\":$second," ||
  fail "the target for request $REQ is not revision 2 of epoch $epoch ($second): $(grep '"topic":"dpc_target"' "$J2")"
echo "ok: the driver published target revision 2, point [0.6, 0.8, 0], request $REQ (read by Cyclone)"

# The reply (VOLATILE) is checked when Cyclone got it; the driver's log confirms the acceptance.
if jq -se --arg r "$REQ" 'map(select(.topic == "dpc_target_reply" and .request_id == $r)) |
                          length > 0' "$J2" >/dev/null; then
  replies=$(grep '"topic":"dpc_target_reply"' "$J2" | grep "\"request_id\":\"$REQ\"")
  jq -se 'all(.accepted)' <<<"$replies" >/dev/null && ! grep -vq "\"revision\":$second," <<<"$replies" ||
    fail "the driver's reply is not 'accepted, revision 2': $replies"
  echo "ok: TargetReply accepted, revision 2 (read by Cyclone)"
else
  echo "note: Cyclone did not receive the driver's TargetReply within 1 s of the new target"
fi
grep -q "target revision $second (request $REQ)" "$WORK/driver.log" ||
  fail "the driver's log does not report target revision $second for $REQ"
echo "ok: dpc-driver logged: $(grep "target revision $second" "$WORK/driver.log" | head -1)"
echo "PASS"
