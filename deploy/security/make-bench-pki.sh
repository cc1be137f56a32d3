#!/usr/bin/env bash
# Makes the keys, certificates, governance and permissions a bench needs for Fast DDS 2.9's
# builtin DDS Security (PKI-DH authentication, Access-Permissions, AES-GCM-GMAC crypto).
#
#   make-bench-pki.sh --out DIR [--bench ID] [--controllers ID,ID...] [--days N]
#                     [--domains MIN-MAX|N] [--rotate [--keep-replaced]] [--revoke-replaced]
#                     [--expired NAME ...]
#
# --out DIR          where everything goes (created). Re-running on an existing DIR keeps what is
#                    there and only adds missing identities (e.g. a new controller id).
# --bench ID         bench id (default bench1): subjects O=dpc-ID, partitions "dpc.ID..."
# --controllers L    controller ids, comma-separated (default main,standby); the controllers
#                    already in DIR are kept too (delete DIR/controller-<id> to retire one)
# --days N           identity certificates' validity (default 365); the CA gets max(N, 3650)
# --domains R        DDS domain ids governed and granted: MIN-MAX or one id (default 0-232)
# --rotate           keep the CA; re-issue every identity key and certificate, rewrite and
#                    re-sign governance and permissions (each file written aside, then mv'd);
#                    the replaced certificates are revoked and DIR/ca/crl.pem (re)written: every
#                    participant that loads it refuses them (a copied old key is useless)
# --keep-replaced    with --rotate: the replaced certificates stay valid for now. For a running
#                    bench: rotate with it, send SIGHUP to every service (each makes its DDS
#                    participant again with its new identity, which the others still accept),
#                    then run --revoke-replaced and send SIGHUP again (each loads the new CRL)
# --revoke-replaced  revoke every certificate this CA issued that is valid and no identity's
#                    current one (replaced by a rotation, or of a retired controller), and write
#                    DIR/ca/crl.pem; nothing else changes
# --expired NAME     (re-)issue NAME's certificate and grant already expired (tests); repeatable
#                    or comma-separated
#
# Layout:  DIR/ca/{ca.key.pem,ca.cert.pem}  ECDSA P-256 self-signed CA, identity and permissions CA
#          DIR/ca/{openssl.cnf,index.txt,serial,newcerts/}  `openssl ca` state (run in DIR/ca)
#          DIR/ca/crl.pem                    after a --rotate: the revoked certificates (10 years)
#          DIR/governance.{xml,p7s}          signed by the CA (openssl smime -sign -text)
#          DIR/<identity>/{key.pem,cert.pem,permissions.xml,permissions.p7s}
# Identities: driver, polarimeter, controller-<id> for each controller id, operator, observer;
# certificate subject /O=dpc-<bench>/CN=<identity>. Keys are ECDSA prime256v1, mode 0600.
# Validity starts one day back: it tolerates clock skew, and Fast DDS parses a grant's dates with
# mktime (local time) while they are written in UTC. A grant's dates are its certificate's.
# Progress goes to stderr.
#
# Use by a participant: properties in its QoS (XML <propertiesPolicy> of the participant
# profile, or DomainParticipantQos::properties()); values are URIs and must start with file://
#   dds.sec.auth.plugin                                     builtin.PKI-DH
#   dds.sec.auth.builtin.PKI-DH.identity_ca                 file://DIR/ca/ca.cert.pem
#   dds.sec.auth.builtin.PKI-DH.identity_certificate        file://DIR/<identity>/cert.pem
#   dds.sec.auth.builtin.PKI-DH.private_key                 file://DIR/<identity>/key.pem
#   dds.sec.auth.builtin.PKI-DH.identity_crl                file://DIR/ca/crl.pem (if it exists)
#   dds.sec.access.plugin                                   builtin.Access-Permissions
#   dds.sec.access.builtin.Access-Permissions.permissions_ca  file://DIR/ca/ca.cert.pem
#   dds.sec.access.builtin.Access-Permissions.governance      file://DIR/governance.p7s
#   dds.sec.access.builtin.Access-Permissions.permissions     file://DIR/<identity>/permissions.p7s
#   dds.sec.crypto.plugin                                   builtin.AES-GCM-GMAC
# Every endpoint must set the DDS partition its grant names: topics of bench B live in "dpc.B",
# a controller C's commands in "dpc.B.controller.C" (read as "dpc.B.controller.*"). An endpoint
# with no partition, or another one, is refused at creation (DataWriter/DataReader is null).
# Unsecured participants are not matched at all. tests/security/run_security_check.sh checks all
# of this against Fast DDS (tests/security/README.md).
set -euo pipefail

# Protection kinds. Every combination of NONE/SIGN/ENCRYPT tried on Fast DDS 2.9.1 matched,
# discovery ENCRYPT with data ENCRYPT included (tests/security/README.md has the runs). Chosen:
# endpoint discovery and liveliness encrypted (topics, types, partitions and QoS are not readable
# on the wire); dpc_* payloads encrypted; every submessage signed (nothing can be injected or
# altered) but not encrypted a second time; no whole-message protection on top (it would encrypt
# everything once more). SPDP and the authentication handshake are always in clear: they carry
# the participant's certificate and its signed permissions document. Each kind can be changed
# for the governance this run writes (DPC_RTPS_PROTECTION, DPC_DISCOVERY_PROTECTION,
# DPC_LIVELINESS_PROTECTION, DPC_METADATA_PROTECTION, DPC_DATA_PROTECTION = NONE|SIGN|ENCRYPT),
# e.g. to measure what each costs (dpc_bus_benchmark --only security); without submessage
# protection (metadata NONE) submessages spoofing a bench writer (its sequence numbers, its
# heartbeats) are not detected.
RTPS_PROTECTION=${DPC_RTPS_PROTECTION:-NONE}
DISCOVERY_PROTECTION=${DPC_DISCOVERY_PROTECTION:-ENCRYPT}
LIVELINESS_PROTECTION=${DPC_LIVELINESS_PROTECTION:-ENCRYPT}
METADATA_PROTECTION=${DPC_METADATA_PROTECTION:-SIGN}
DATA_PROTECTION=${DPC_DATA_PROTECTION:-ENCRYPT}
TOPICS="dpc_stokes_sample dpc_waveplate_command dpc_waveplate_state dpc_controller_status
        dpc_device_description dpc_target dpc_target_request dpc_target_reply dpc_bench_summary"

OUT="" BENCH=bench1 CONTROLLERS=main,standby DAYS=365 DOMAINS="" ROTATE=0 EXPIRED="" REVOKED=0
KEEP_REPLACED=0 REVOKE_REPLACED=0 CONTROLLERS_GIVEN=0
usage() { awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "${BASH_SOURCE[0]}" >&2; exit 2; }
die() { echo "make-bench-pki.sh: $*" >&2; exit 2; }
for kind in RTPS DISCOVERY LIVELINESS METADATA DATA; do
  value=${kind}_PROTECTION
  [[ "${!value}" =~ ^(NONE|SIGN|ENCRYPT)$ ]] || die "DPC_${kind}_PROTECTION=${!value}: NONE, SIGN or ENCRYPT"
done
while [[ $# -gt 0 ]]; do
  case $1 in
    --out) OUT=${2:?}; shift 2 ;;
    --bench) BENCH=${2:?}; shift 2 ;;
    --controllers) CONTROLLERS=${2:?}; CONTROLLERS_GIVEN=1; shift 2 ;;
    --days) DAYS=${2:?}; shift 2 ;;
    --domains) DOMAINS=${2:?}; shift 2 ;;
    --rotate) ROTATE=1; shift ;;
    --keep-replaced) KEEP_REPLACED=1; shift ;;
    --revoke-replaced) REVOKE_REPLACED=1; shift ;;
    --expired) EXPIRED+=" ${2:?}"; shift 2
               while [[ $# -gt 0 && $1 != --* ]]; do EXPIRED+=" $1"; shift; done ;;
    -h|--help) usage ;;
    *) echo "make-bench-pki.sh: unknown argument $1" >&2; usage ;;
  esac
done
[[ -n $OUT ]] || usage
[[ $KEEP_REPLACED == 0 || $ROTATE == 1 ]] || die "--keep-replaced goes with --rotate"
[[ $KEEP_REPLACED == 0 || $REVOKE_REPLACED == 0 ]] || die "--keep-replaced and --revoke-replaced contradict each other"
if [[ $REVOKE_REPLACED == 1 && $CONTROLLERS_GIVEN == 0 ]]; then
  # Revoking adds no identity: the controllers are the directory's own.
  CONTROLLERS=$(find "$OUT" -mindepth 1 -maxdepth 1 -type d -name 'controller-*' -printf '%f\n' 2>/dev/null |
                sed 's/^controller-//' | sort | paste -sd, -)
  [[ -n $CONTROLLERS ]] || die "$OUT has no controller identity: nothing of a bench to revoke"
fi
name_re='^[A-Za-z0-9_-]+$'
[[ $BENCH =~ $name_re ]] || die "bad bench id '$BENCH'"
[[ $DAYS =~ ^[1-9][0-9]*$ ]] || die "bad --days '$DAYS'"
domain_xml() {  # MIN-MAX or N → the <domains> content
  if [[ $1 =~ ^([0-9]+)-([0-9]+)$ ]] && ((BASH_REMATCH[1] <= BASH_REMATCH[2] && BASH_REMATCH[2] <= 232)); then
    echo "<id_range><min>${BASH_REMATCH[1]}</min><max>${BASH_REMATCH[2]}</max></id_range>"
  elif [[ $1 =~ ^[0-9]+$ ]] && (($1 <= 232)); then
    echo "<id>$1</id>"
  else
    die "bad --domains '$1' (MIN-MAX or N, ids 0-232)"
  fi
}
# Without --domains, an existing governance's domains stay (and new grants get them).
if [[ -z $DOMAINS && -s $OUT/governance.xml ]]; then
  DOMAIN_XML=$(sed -n 's|^ *<domains>\(.*\)</domains>$|\1|p' "$OUT/governance.xml" | head -n 1)
  [[ -n $DOMAIN_XML ]] || die "cannot read the domains of $OUT/governance.xml: give --domains"
  DOMAINS=$(sed 's/<[a-z_]*>//g; s|</max></id_range>||; s|</min></[a-z]*>|-|; s|</id>||' <<<"$DOMAIN_XML")
else
  DOMAINS=${DOMAINS:-0-232}
  DOMAIN_XML=$(domain_xml "$DOMAINS")
  if [[ $ROTATE == 0 && -s $OUT/governance.xml ]] && ! grep -qF "<domains>$DOMAIN_XML</domains>" "$OUT/governance.xml"; then
    die "$OUT/governance.xml governs other domains than $DOMAINS: add --rotate to change them"
  fi
fi
IDENTITIES=(driver polarimeter)
IFS=',' read -r -a controller_ids <<<"$CONTROLLERS"
[[ ${#controller_ids[@]} -gt 0 ]] || die "no controller id"
# Controllers issued by an earlier run stay identities of the bench (kept, or rotated with the
# rest); to retire one, delete DIR/controller-<id>.
for cert in "$OUT"/controller-*/cert.pem; do
  [[ -e $cert ]] || continue
  id=$(basename "$(dirname "$cert")"); id=${id#controller-}
  [[ ",$CONTROLLERS," == *",$id,"* ]] || controller_ids+=("$id")
done
for id in "${controller_ids[@]}"; do
  [[ $id =~ $name_re ]] || die "bad controller id '$id'"
  IDENTITIES+=("controller-$id")
done
IDENTITIES+=(operator observer)
EXPIRED=${EXPIRED//,/ }
for name in $EXPIRED; do
  [[ " ${IDENTITIES[*]} " == *" $name "* ]] || die "--expired $name: not one of ${IDENTITIES[*]}"
done
command -v openssl >/dev/null || die "openssl not found"

mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
CA=$OUT/ca
B="dpc.$BENCH"
ORG="dpc-$BENCH"
TMP=$(mktemp -d "$OUT/.tmp.XXXXXX")
trap 'rm -rf "$TMP"; rm -f "$OUT"/.*.new "$OUT"/*/.*.new' EXIT
log() { echo "$*" >&2; }
# openssl ca wants YYYYMMDDHHMMSSZ; permissions want YYYY-MM-DDTHH:MM:SS (both UTC here).
asn1_time() { date -u -d "$1" +%Y%m%d%H%M%SZ; }
cert_date() { date -u -d "$(openssl x509 -noout "-$2" -in "$1" | cut -d= -f2)" +%Y-%m-%dT%H:%M:%S; }
new_key() { (umask 077 && openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:prime256v1 \
  -pkeyopt ec_param_enc:named_curve -out "$1" 2>/dev/null); }
ca() { (cd "$CA" && openssl ca -batch -config openssl.cnf -notext "$@" 2>"$TMP/ca.log") ||
  { cat "$TMP/ca.log" >&2; die "openssl ca failed"; }; }
sign() { openssl smime -sign -text -in "$1" -out "$2" -signer "$CA/ca.cert.pem" -inkey "$CA/ca.key.pem"; }
# install_into DIR FILE...: move each DIR/.FILE.new over DIR/FILE (a rename: atomic per file).
install_into() { local dir=$1; shift; for f in "$@"; do mv -f "$dir/.$f.new" "$dir/$f"; done; }

# ---- CA ------------------------------------------------------------------------------------
if [[ -s $CA/ca.cert.pem && -s $CA/ca.key.pem ]]; then
  subject=$(openssl x509 -noout -subject -nameopt RFC2253 -in "$CA/ca.cert.pem")
  [[ $subject == "subject=CN=dpc $BENCH CA,O=$ORG" ]] || die "$CA is not bench $BENCH's CA ($subject)"
  log "kept CA ${subject#subject=}"
else
  [[ ! -e $CA/ca.key.pem ]] || die "$CA/ca.key.pem exists without its certificate: remove DIR/ca"
  mkdir -p "$CA/newcerts" && chmod 700 "$CA"
  : >"$CA/index.txt"
  openssl rand -hex 8 >"$CA/serial"
  cat >"$CA/openssl.cnf" <<'EOF'
# Written by deploy/security/make-bench-pki.sh; used as `openssl ca -config openssl.cnf` in this dir.
[ ca ]
default_ca = dpc_ca
[ dpc_ca ]
dir = .
database = $dir/index.txt
new_certs_dir = $dir/newcerts
certificate = $dir/ca.cert.pem
private_key = $dir/ca.key.pem
serial = $dir/serial
default_md = sha256
policy = policy_bench
unique_subject = no
email_in_dn = no
copy_extensions = none
preserve = yes
[ policy_bench ]
organizationName = supplied
commonName = supplied
[ req ]
distinguished_name = req_dn
[ req_dn ]
[ v3_ca ]
basicConstraints = critical, CA:true
keyUsage = critical, keyCertSign, cRLSign, digitalSignature
subjectKeyIdentifier = hash
[ v3_identity ]
basicConstraints = critical, CA:false
keyUsage = critical, digitalSignature, keyAgreement
subjectKeyIdentifier = hash
authorityKeyIdentifier = keyid
EOF
  new_key "$CA/ca.key.pem"
  openssl req -new -config "$CA/openssl.cnf" -key "$CA/ca.key.pem" -subj "/O=$ORG/CN=dpc $BENCH CA" \
    -out "$TMP/ca.csr"
  ca_days=$((DAYS > 3650 ? DAYS : 3650))
  ca -selfsign -keyfile ca.key.pem -extensions v3_ca -in "$TMP/ca.csr" -out "$TMP/ca.cert.pem" \
    -startdate "$(asn1_time '1 day ago')" -enddate "$(asn1_time "$ca_days days")"
  mv "$TMP/ca.cert.pem" "$CA/ca.cert.pem"
  log "made CA CN=dpc $BENCH CA,O=$ORG in $CA (valid until $(cert_date "$CA/ca.cert.pem" enddate))"
fi

# ---- governance ----------------------------------------------------------------------------
governance_xml() {
  cat <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<!-- Bench $BENCH governance, made by deploy/security/make-bench-pki.sh -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains>$DOMAIN_XML</domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>$DISCOVERY_PROTECTION</discovery_protection_kind>
      <liveliness_protection_kind>$LIVELINESS_PROTECTION</liveliness_protection_kind>
      <rtps_protection_kind>$RTPS_PROTECTION</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>dpc_*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>false</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>$METADATA_PROTECTION</metadata_protection_kind>
          <data_protection_kind>$DATA_PROTECTION</data_protection_kind>
        </topic_rule>
        <topic_rule>
          <!-- any other topic: access controlled, and no grant names one, so it is denied -->
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>false</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>$METADATA_PROTECTION</metadata_protection_kind>
          <data_protection_kind>$DATA_PROTECTION</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
EOF
}
if [[ $ROTATE == 1 || ! -s $OUT/governance.p7s || ! -s $OUT/governance.xml ]]; then
  governance_xml >"$OUT/.governance.xml.new"
  sign "$OUT/.governance.xml.new" "$OUT/.governance.p7s.new"
  install_into "$OUT" governance.xml governance.p7s
  log "signed governance (domains $DOMAINS; protection: rtps $RTPS_PROTECTION, discovery $DISCOVERY_PROTECTION," \
    "liveliness $LIVELINESS_PROTECTION, metadata $METADATA_PROTECTION, data $DATA_PROTECTION)"
else
  log "kept governance (domains $DOMAINS)"
fi

# ---- permissions ---------------------------------------------------------------------------
# Fast DDS 2.9 takes the first <allow_rule> naming a topic and checks the endpoint's partitions
# against every partition of that rule's publish (or subscribe) criteria. So each rule below has
# one partition set, and a topic is named in one publish rule and one subscribe rule at most.
rule() {  # rule publish|subscribe "PARTITION..." TOPIC...
  local kind=$1 parts=$2 p t; shift 2
  echo "      <allow_rule>"
  echo "        <domains>$DOMAIN_XML</domains>"
  echo "        <$kind>"
  echo "          <topics>"; for t in "$@"; do echo "            <topic>$t</topic>"; done; echo "          </topics>"
  echo "          <partitions>"; for p in $parts; do echo "            <partition>$p</partition>"; done; echo "          </partitions>"
  echo "        </$kind>"
  echo "      </allow_rule>"
}
grant_rules() {
  local ctl="$B.controller"
  case $1 in
    driver)
      rule publish "$B" dpc_waveplate_state dpc_device_description dpc_target dpc_target_reply
      # dpc_target: another driver on the bench shows itself by its target (driver main.cc)
      rule subscribe "$B" dpc_stokes_sample dpc_target_request dpc_controller_status dpc_target
      rule subscribe "$ctl.*" dpc_waveplate_command ;;
    polarimeter)
      rule publish "$B" dpc_stokes_sample dpc_bench_summary
      rule subscribe "$B" dpc_waveplate_state dpc_device_description dpc_target ;;
    controller-*)
      rule publish "$ctl.${1#controller-}" dpc_waveplate_command
      rule publish "$B" dpc_controller_status
      rule subscribe "$B" dpc_stokes_sample dpc_waveplate_state dpc_device_description dpc_target ;;
    operator)
      rule publish "$B" dpc_target_request
      # shellcheck disable=SC2086
      rule subscribe "$B $ctl.*" $TOPICS ;;
    observer)
      # shellcheck disable=SC2086
      rule subscribe "$B $ctl.*" $TOPICS ;;
  esac
}
permissions_xml() {  # permissions_xml IDENTITY CERT
  cat <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<!-- $1 of bench $BENCH, made by deploy/security/make-bench-pki.sh -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$BENCH.$1">
      <subject_name>CN=$1,O=$ORG</subject_name>
      <validity>
        <not_before>$(cert_date "$2" startdate)</not_before>
        <not_after>$(cert_date "$2" enddate)</not_after>
      </validity>
$(grant_rules "$1")
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
EOF
}

# ---- identities ----------------------------------------------------------------------------
for name in "${IDENTITIES[@]}"; do
  dir=$OUT/$name
  expired=0; [[ " $EXPIRED " == *" $name "* ]] && expired=1
  if [[ $ROTATE == 0 && $expired == 0 && -s $dir/key.pem && -s $dir/cert.pem && -s $dir/permissions.p7s ]]; then
    state=""
    openssl x509 -checkend 0 -noout -in "$dir/cert.pem" >/dev/null || state=", EXPIRED: use --rotate"
    # The grant follows this script's rules (a topic added since they were signed, say): kept
    # identities get their permissions signed again when the rules changed.
    permissions_xml "$name" "$dir/cert.pem" >"$dir/.permissions.xml.new"
    if cmp -s "$dir/.permissions.xml.new" "$dir/permissions.xml"; then
      rm -f "$dir/.permissions.xml.new"
      log "kept $name (valid until $(cert_date "$dir/cert.pem" enddate)$state)"
    else
      sign "$dir/.permissions.xml.new" "$dir/.permissions.p7s.new"
      install_into "$dir" permissions.xml permissions.p7s
      log "kept $name (valid until $(cert_date "$dir/cert.pem" enddate)$state), its permissions updated"
    fi
    continue
  fi
  mkdir -p "$dir"
  if [[ $ROTATE == 1 && $KEEP_REPLACED == 0 && -s $dir/cert.pem ]]; then
    # The certificate replaced is revoked (if this CA issued it and it is not revoked yet).
    serial=$(openssl x509 -noout -serial -in "$dir/cert.pem" 2>/dev/null || true)
    serial=${serial#serial=}
    if [[ -n $serial ]] && awk -F'\t' -v s="$serial" '$1 == "V" && $4 == s { f = 1 } END { exit !f }' "$CA/index.txt"; then
      ca -revoke "$dir/cert.pem" -crl_reason superseded
      REVOKED=$((REVOKED + 1))
    fi
  fi
  new_key "$dir/.key.pem.new"
  openssl req -new -config "$CA/openssl.cnf" -key "$dir/.key.pem.new" -subj "/O=$ORG/CN=$name" -out "$TMP/$name.csr"
  if [[ $expired == 1 ]]; then
    dates=(-startdate "$(asn1_time '2 days ago')" -enddate "$(asn1_time '1 day ago')")
  else
    dates=(-startdate "$(asn1_time '1 day ago')" -enddate "$(asn1_time "$DAYS days")")
  fi
  ca -extensions v3_identity "${dates[@]}" -in "$TMP/$name.csr" -out "$dir/.cert.pem.new"
  permissions_xml "$name" "$dir/.cert.pem.new" >"$dir/.permissions.xml.new"
  sign "$dir/.permissions.xml.new" "$dir/.permissions.p7s.new"
  install_into "$dir" key.pem cert.pem permissions.xml permissions.p7s
  log "issued $name (valid until $(cert_date "$dir/cert.pem" enddate)$([[ $expired == 1 ]] && echo ', EXPIRED'))"
done
if [[ $KEEP_REPLACED == 1 ]]; then
  log "the replaced certificates stay valid until --revoke-replaced (send SIGHUP to every service first)"
fi
if [[ $REVOKE_REPLACED == 1 ]]; then
  # The CA's own certificate is in the index too (self-signed by `openssl ca`): never revoked.
  serial=$(openssl x509 -noout -serial -in "$CA/ca.cert.pem")
  current=" ${serial#serial=} "
  for name in "${IDENTITIES[@]}"; do
    serial=$(openssl x509 -noout -serial -in "$OUT/$name/cert.pem")
    current+="${serial#serial=} "
  done
  # index.txt: status, expiry, revocation, serial, file, subject (tab-separated).
  mapfile -t replaced < <(awk -F'\t' '$1 == "V" { print $4 }' "$CA/index.txt")
  for serial in "${replaced[@]}"; do
    [[ $current == *" $serial "* ]] && continue
    ca -revoke "newcerts/$serial.pem" -crl_reason superseded
    REVOKED=$((REVOKED + 1))
  done
  [[ $REVOKED -gt 0 ]] || log "no replaced certificate left to revoke"
fi
if [[ $REVOKED -gt 0 ]]; then
  # Ten years: an expired CRL would make Fast DDS refuse every certificate of the CA.
  ca -gencrl -crldays 3650 -out "$CA/.crl.pem.new"
  install_into "$CA" crl.pem
  log "revoked $REVOKED replaced certificates: $CA/crl.pem"
fi
