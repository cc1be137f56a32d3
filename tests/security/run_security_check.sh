#!/usr/bin/env bash
# Checks deploy/security/make-bench-pki.sh against Fast DDS 2.9's builtin DDS Security: makes a
# bench's PKI (and a second CA, an expired certificate, tampered governance and permissions),
# then runs pairs of tests/security/security_probe.cc (a publisher and a subscriber at the same
# time, loopback only, domains 200-230) and prints one table row per case, with what was
# expected. Exits 1 if a case did not go as expected.
#
#   run_security_check.sh [--work DIR] [--seconds S] [--probe BINARY] [--keep]
#
# --work DIR     where the PKIs, the probe and the logs go (default: a new /tmp/dpc-security.*,
#                removed at the end unless --keep)
# --seconds S    how long each probe runs (default 4)
# --probe BIN    use this security_probe instead of building one (g++, libfastrtps-dev)
# As root, the first case is also sniffed on lo (loopback_sniff.py): the sample text and the
# probe's type name must not appear in clear. Not part of ctest (needs ~1.5 min, 2 cores).
set -euo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
MAKE_PKI=$ROOT/deploy/security/make-bench-pki.sh
WORK="" SECONDS_PER_CASE=4 PROBE="" KEEP=0
usage() { awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "${BASH_SOURCE[0]}" >&2; exit 2; }
while [[ $# -gt 0 ]]; do
  case $1 in
    --work) WORK=${2:?}; shift 2 ;;
    --seconds) SECONDS_PER_CASE=${2:?}; shift 2 ;;
    --probe) PROBE=${2:?}; shift 2 ;;
    --keep) KEEP=1; shift ;;
    -h|--help) usage ;;
    *) echo "run_security_check.sh: unknown argument $1" >&2; usage ;;
  esac
done
if [[ -z $WORK ]]; then
  WORK=$(mktemp -d /tmp/dpc-security.XXXXXX)
  [[ $KEEP == 1 ]] || trap 'rm -rf "$WORK"' EXIT
fi
mkdir -p "$WORK/logs"
if [[ -z $PROBE ]]; then
  PROBE=$WORK/security_probe
  echo "building $PROBE" >&2
  g++ -O1 -std=c++17 -o "$PROBE" "$HERE/security_probe.cc" -lfastrtps -lfastcdr
fi

# ---- the PKIs ------------------------------------------------------------------------------
B=dpc.bench1
GOOD=$WORK/bench1
pki() { "$MAKE_PKI" "$@" 2>>"$WORK/logs/make-bench-pki.log"; }
pki --out "$GOOD"
pki --out "$WORK/other-ca"                          # same bench and subjects, another CA
cp -a "$GOOD" "$WORK/expired" && pki --out "$WORK/expired" --expired driver
cp -a "$GOOD" "$WORK/tampered-governance"          # one byte of the signed text: domains 1-232
sed -i '0,/<min>0<\/min>/s//<min>1<\/min>/' "$WORK/tampered-governance/governance.p7s"
cp -a "$GOOD" "$WORK/tampered-permissions"         # one byte: the grant's last year + 1
year=$(sed -n 's/.*<not_after>\([0-9]*\)-.*/\1/p' "$GOOD/driver/permissions.xml")
sed -i "s/<not_after>$year-/<not_after>$((year + 1))-/" "$WORK/tampered-permissions/driver/permissions.p7s"
one_byte() { [[ $({ cmp -l "$1" "$2" || true; } | wc -l) == 1 ]] || { echo "tampering $2 failed" >&2; exit 2; }; }
one_byte "$GOOD/governance.p7s" "$WORK/tampered-governance/governance.p7s"
one_byte "$GOOD/driver/permissions.p7s" "$WORK/tampered-permissions/driver/permissions.p7s"

# ---- the cases -----------------------------------------------------------------------------
DOMAIN=200
FAILED=0
printf '| %-56s | %-9s | %-50s | %-50s | %-4s |\n' case expected publisher subscriber ok
printf '|%s|%s|%s|%s|%s|\n' "$(printf -- '-%.0s' {1..58})" -----------  \
  "$(printf -- '-%.0s' {1..52})" "$(printf -- '-%.0s' {1..52})" ------
summary() {  # summary RESULT_LINE -> "created matched=N first=T ms written/received=N"
  local line=$1 created matched first written received
  [[ -n $line ]] || { echo "no output"; return; }
  created=$(sed -n 's/.* created=\([^ ]*\).*/\1/p' <<<"$line")
  matched=$(sed -n 's/.* matched=\([0-9]*\).*/\1/p' <<<"$line")
  first=$(sed -n 's/.* first_match_ms=\([-0-9]*\).*/\1/p' <<<"$line")
  written=$(sed -n 's/.* written=\([0-9]*\).*/\1/p' <<<"$line")
  received=$(sed -n 's/.* received=\([0-9]*\).*/\1/p' <<<"$line")
  if [[ $created != yes ]]; then echo "REFUSED ($created)"; return; fi
  echo "matched=$matched$([[ $first != -1 ]] && echo " at ${first}ms") $([[ $written != 0 ]] && echo "written=$written" || echo "received=$received")"
}
# pair NAME EXPECT(data|none) PUB_DIR PUB_ID PUB_PARTITION SUB_DIR SUB_ID SUB_PARTITION [TOPIC]
pair() {
  local name=$1 expect=$2 topic=${9:-dpc_waveplate_state} log=$WORK/logs/$DOMAIN
  "$PROBE" --dir "$6" --identity "$7" --role sub --topic "$topic" --partition "$8" --domain $DOMAIN \
    --seconds "$SECONDS_PER_CASE" >"$log.sub" 2>"$log.sub.err" &
  local sub_pid=$!
  "$PROBE" --dir "$3" --identity "$4" --role pub --topic "$topic" --partition "$5" --domain $DOMAIN \
    --seconds "$SECONDS_PER_CASE" >"$log.pub" 2>"$log.pub.err" || true
  wait $sub_pid || true
  local pub sub ok=yes
  pub=$(cat "$log.pub") sub=$(cat "$log.sub")
  local sub_received; sub_received=$(sed -n 's/.* received=\([0-9]*\).*/\1/p' <<<"$sub")
  local pub_matched; pub_matched=$(sed -n 's/.* created=yes matched=\([0-9]*\).*/\1/p' <<<"$pub")
  local sub_matched; sub_matched=$(sed -n 's/.* created=yes matched=\([0-9]*\).*/\1/p' <<<"$sub")
  if [[ $expect == data ]]; then
    [[ ${pub_matched:-0} -ge 1 && ${sub_matched:-0} -ge 1 && ${sub_received:-0} -gt 0 ]] || ok=NO
  else
    [[ ${pub_matched:-0} == 0 && ${sub_matched:-0} == 0 && ${sub_received:-0} == 0 ]] || ok=NO
  fi
  [[ $ok == yes ]] || FAILED=1
  printf '| %-56s | %-9s | %-50s | %-50s | %-4s |\n' "$name (d$DOMAIN)" "$expect" \
    "$(summary "$pub")" "$(summary "$sub")" "$ok"
  DOMAIN=$((DOMAIN + 1))
}

if [[ $EUID == 0 ]]; then
  python3 "$HERE/loopback_sniff.py" $((SECONDS_PER_CASE + 1)) $DOMAIN "driver #" "dpc_probe::Sample" \
    >"$WORK/logs/sniff" 2>"$WORK/logs/sniff.err" &
  sniff_pid=$!
  for _ in $(seq 50); do grep -q listening "$WORK/logs/sniff.err" 2>/dev/null && break; sleep 0.1; done
fi
pair "driver -> observer, state" data "$GOOD" driver $B "$GOOD" observer $B
if [[ $EUID == 0 ]]; then
  wait "$sniff_pid"
  sniffed=$(tr '\n' ';' <"$WORK/logs/sniff")
  if grep -q ': [1-9][0-9]* datagrams in clear' "$WORK/logs/sniff"; then FAILED=1; fi
fi
pair "controller-main -> driver, command" data "$GOOD" controller-main $B.controller.main "$GOOD" driver "$B.controller.*" dpc_waveplate_command
pair "controller-main in standby's partition" none "$GOOD" controller-main $B.controller.standby "$GOOD" driver "$B.controller.*" dpc_waveplate_command
pair "controller-main command in $B" none "$GOOD" controller-main $B "$GOOD" driver "$B.controller.*" dpc_waveplate_command
pair "observer publishes a command" none "$GOOD" observer $B.controller.main "$GOOD" driver "$B.controller.*" dpc_waveplate_command
pair "no credentials -> observer" none "$GOOD" none $B "$GOOD" observer $B
pair "driver -> no credentials" none "$GOOD" driver $B "$GOOD" none $B
pair "driver of a second CA -> observer" none "$WORK/other-ca" driver $B "$GOOD" observer $B
pair "expired driver -> observer" none "$WORK/expired" driver $B "$GOOD" observer $B
pair "tampered governance driver -> observer" none "$WORK/tampered-governance" driver $B "$GOOD" observer $B
pair "tampered permissions driver -> observer" none "$WORK/tampered-permissions" driver $B "$GOOD" observer $B
pair "driver, topic not in governance" none "$GOOD" driver $B "$GOOD" observer $B other_topic
pair "driver, no partition" none "$GOOD" driver "" "$GOOD" observer ""
pair "observer reads bench2" none "$GOOD" driver $B "$GOOD" observer dpc.bench2
pair "polarimeter -> controller-standby, samples" data "$GOOD" polarimeter $B "$GOOD" controller-standby $B dpc_stokes_sample
pair "operator -> driver, target request" data "$GOOD" operator $B "$GOOD" driver $B dpc_target_request
pair "controller-standby -> operator, command" data "$GOOD" controller-standby $B.controller.standby "$GOOD" operator "$B,$B.controller.*" dpc_waveplate_command

# Re-running keeps everything; --rotate keeps the CA and replaces every identity.
sums() { (cd "$1" && find . -path ./ca/newcerts -prune -o -type f \( -name '*.pem' -o -name '*.p7s' -o -name '*.xml' \) \
  -print | sort | xargs sha256sum); }
before=$(sums "$GOOD")
pki --out "$GOOD"
idem=yes; [[ $(sums "$GOOD") == "$before" ]] || { idem=NO; FAILED=1; }
pki --out "$GOOD" --controllers main,standby,spare
changed=$(diff <(echo "$before") <(sums "$GOOD") | grep -c '^>' || true)
added=yes; [[ $changed == 4 && -s $GOOD/controller-spare/cert.pem ]] || { added=NO; FAILED=1; }
cp -a "$GOOD" "$WORK/before-rotation"
pki --out "$GOOD" --rotate
rotated=yes
for key in "$GOOD"/*/key.pem; do
  if cmp -s "$key" "$WORK/before-rotation/${key#"$GOOD"/}"; then rotated="NO ($key kept)"; FAILED=1; fi
done
kept_ca=yes
for f in ca.cert.pem ca.key.pem; do
  cmp -s "$GOOD/ca/$f" "$WORK/before-rotation/ca/$f" || { kept_ca=NO; FAILED=1; }
done
pair "rotated driver -> rotated observer" data "$GOOD" driver $B "$GOOD" observer $B
# The rotation revoked the old certificates: a participant of the old files (which has no CRL
# yet) is refused by the rotated ones, which load the CRL.
revoked=yes
[[ -s $GOOD/ca/crl.pem ]] && [[ $(openssl crl -in "$GOOD/ca/crl.pem" -noout -text | grep -c "Serial Number") -ge 7 ]] ||
  { revoked=NO; FAILED=1; }
pair "pre-rotation driver -> rotated observer (revoked)" none "$WORK/before-rotation" driver $B "$GOOD" observer $B

echo
echo "re-run without --rotate changes nothing: $idem; adding controller spare changed 4 files only: $added"
echo "--rotate replaced every identity's key (controller-spare too): $rotated; CA kept: $kept_ca; old certificates revoked (crl.pem): $revoked"
[[ -z ${sniffed:-} ]] || echo "on the wire during the first case (its domain only): $sniffed"
[[ $KEEP == 0 ]] || echo "kept $WORK"
exit $FAILED
