#!/usr/bin/env bash
# The image's entrypoint: picks the Fast DDS profile from the environment, then execs the
# command (so the service is PID 1 and receives docker's SIGTERM itself).
#
# Environment (the first that is set wins):
#   FASTRTPS_DEFAULT_PROFILES_FILE   a profile file of your own (mounted): used as is
#   DPC_DDS_DISCOVERY_SERVER=ADDR[:PORT]   this container IS the discovery server: runs
#                                    fast-discovery-server bound to ADDR only (no command needed)
#   DPC_DDS_SERVER=ADDR[:PORT]       a CLIENT of that discovery server
#   DPC_DDS_PEERS=ADDR,ADDR,...      unicast discovery with these fixed peers (no multicast)
#   DPC_DDS_ADDRESS=ADDR             this container's address (default: `hostname -i`); the UDPv4
#                                    transport is whitelisted to it and nothing else. The
#                                    entrypoint waits (DPC_DDS_WAIT_S, 60 s) until the interface
#                                    holding it is up: Fast DDS drops a whitelisted address whose
#                                    interface is down (a container on the host's network, e.g.
#                                    the dashboard, whitelists the bench bridge's gateway, and
#                                    that bridge is down until a bench container attaches)
# With none of them, the services use their compiled-in loopback profile (this container only).
#
# DDS Security:
#   DPC_SECURITY_DIR=DIR   the bench's credentials (make-bench-pki.sh); every service and dpc
#                          command takes its identity from there (DPC_IDENTITY, or its role). The
#                          entrypoint waits (DPC_SECURITY_WAIT_S, 60 s) for DIR/ready, which the
#                          compose file's pki service writes once the credentials are made.
#   DPC_SECURITY=off       run without security even if DPC_SECURITY_DIR is set
#   command "make-bench-pki --out PRIVATE ARGS…"   (as root) makes the credentials with ARGS in
#                          PRIVATE and gives each container a directory in DPC_PKI_PUBLIC with
#                          only its identity (never the CA's key): <identity>/ for each one,
#                          tools/ with operator and observer; hands them to DPC_PKI_OWNER
#                          (10001:10001, the image's dpc user) and writes ready in each;
#                          also hands DPC_RECORDINGS (the recorder's directory), if mounted, to
#                          that user
set -euo pipefail

fastdds_dir="${DPC_FASTDDS_DIR:-/opt/dpc/share/dpc/fastdds}"
profile="${TMPDIR:-/tmp}/dpc-fastdds-profile.xml"

fail() { echo "dpc-entrypoint: $*" >&2; exit 2; }
own_address() {
  if [[ -n "${DPC_DDS_ADDRESS:-}" ]]; then echo "$DPC_DDS_ADDRESS"; return; fi
  local address
  address=$(hostname -i 2>/dev/null | awk '{print $1}')
  [[ -n "$address" ]] || fail "cannot tell this container's address: set DPC_DDS_ADDRESS"
  echo "$address"
}

# interface_of ADDRESS: the interface whose route covers the IPv4 ADDRESS (/proc/net/route:
# destination and mask in the kernel's byte order, little-endian here).
interface_of() {
  local a b c d address iface destination mask rest
  [[ $1 != 127.* ]] || { echo lo; return 0; }
  IFS=. read -r a b c d <<<"$1"
  address=$((a | b << 8 | c << 16 | d << 24))
  while read -r iface destination _ _ _ _ _ mask rest; do
    [[ $iface != Iface && $mask != 00000000 ]] || continue
    if (((address & 16#$mask) == 16#$destination)); then echo "$iface"; return 0; fi
  done </proc/net/route
  return 1
}

# wait_for_interface ADDRESS: until the interface holding ADDRESS is up (DPC_DDS_WAIT_S).
wait_for_interface() {
  local iface="" waited=0
  until iface=$(interface_of "$1") && [[ "$(cat "/sys/class/net/$iface/operstate" 2>/dev/null)" != down ]]; do
    ((waited < ${DPC_DDS_WAIT_S:-60} * 5)) ||
      fail "no interface up with a route to DPC_DDS_ADDRESS=$1${iface:+ ($iface is down)} (is the bench up?)"
    ((waited)) || echo "dpc-entrypoint: waiting for the interface of $1${iface:+ ($iface)} to come up" >&2
    waited=$((waited + 1))
    sleep 0.2
  done
}

# client_profile OPTION VARIABLE DESCRIPTION: this container's profile from make_profile.sh
# --address <own address> OPTION "${!VARIABLE}", used by every participant the command starts.
client_profile() {
  local address
  address=$(own_address)
  [[ ! $address =~ ^[0-9]+\.[0-9]+\.[0-9]+\.[0-9]+$ ]] || wait_for_interface "$address"
  "$fastdds_dir/make_profile.sh" --address "$address" "$1" "${!2}" >"$profile" ||
    fail "bad $2=${!2} or DPC_DDS_ADDRESS=$address"
  export FASTRTPS_DEFAULT_PROFILES_FILE="$profile"
  echo "dpc-entrypoint: UDPv4 on $address, $3" >&2
}

if [[ "${1:-}" == "make-bench-pki" ]]; then
  # make-bench-pki --out PRIVATE ARGS…: the CA and everything in PRIVATE (the CA's key never
  # leaves it). Each container gets a directory of its own in DPC_PKI_PUBLIC holding only what
  # it needs: the CA certificate, the governance and its identity's key, certificate and
  # permissions (the layout --security-dir reads): DPC_PKI_PUBLIC/<identity>/ for every
  # identity, and DPC_PKI_PUBLIC/tools/ with the operator and the observer. Written in place
  # (the directories may already be bind-mounted), handed to DPC_PKI_OWNER, marked ready.
  shift
  out=""
  for ((i = 1; i <= $#; i++)); do [[ "${!i}" == "--out" ]] && { j=$((i + 1)); out="${!j}"; }; done
  [[ -n "$out" ]] || fail "make-bench-pki needs --out DIR"
  public="${DPC_PKI_PUBLIC:?make-bench-pki needs DPC_PKI_PUBLIC}"
  mkdir -p "$public"
  rm -f "$public"/*/ready
  make-bench-pki "$@"
  grant() {  # grant CONTAINER IDENTITY…
    local dir="$public/$1" identity
    shift
    mkdir -p "$dir/ca"
    rm -f "$dir/ready"
    # Only what this container needs: nothing left from an earlier run or another identity.
    find "$dir" -mindepth 1 -maxdepth 1 ! -name ca -exec rm -rf {} +
    cp "$out/ca/ca.cert.pem" "$dir/ca/"
    [[ ! -s "$out/ca/crl.pem" ]] || cp "$out/ca/crl.pem" "$dir/ca/"  # certificates a rotation revoked
    cp "$out/governance.p7s" "$dir/"
    for identity in "$@"; do
      mkdir -p "$dir/$identity"
      cp "$out/$identity"/key.pem "$out/$identity"/cert.pem "$out/$identity"/permissions.p7s "$dir/$identity/"
    done
    chown -R "${DPC_PKI_OWNER:-10001:10001}" "$dir"
    touch "$dir/ready"
  }
  for identity in "$out"/*/; do
    name=$(basename "$identity")
    [[ "$name" == ca ]] || grant "$name" "$name"
  done
  grant tools operator observer
  echo "dpc-entrypoint: credentials in $public/<identity> and $public/tools (the CA and its key in $out)" >&2
  # The recorder's directory on the host (a bind mount Docker creates as root): handed to the
  # image's user, whom the recorder runs as.
  if [[ -n "${DPC_RECORDINGS:-}" && -d "$DPC_RECORDINGS" ]]; then
    chown "${DPC_PKI_OWNER:-10001:10001}" "$DPC_RECORDINGS"
    echo "dpc-entrypoint: recordings go to $DPC_RECORDINGS (owner ${DPC_PKI_OWNER:-10001:10001})" >&2
  fi
  exit 0
fi

if [[ "${DPC_SECURITY:-on}" == "off" ]]; then
  unset DPC_SECURITY_DIR
elif [[ -n "${DPC_SECURITY_DIR:-}" ]]; then
  waited=0
  until [[ -e "$DPC_SECURITY_DIR/ready" ]]; do
    ((waited < ${DPC_SECURITY_WAIT_S:-60} * 5)) || fail "no credentials in DPC_SECURITY_DIR=$DPC_SECURITY_DIR (is the pki service done?)"
    ((waited)) || echo "dpc-entrypoint: waiting for the credentials in $DPC_SECURITY_DIR" >&2
    waited=$((waited + 1))
    sleep 0.2
  done
  export DPC_SECURITY_DIR
  echo "dpc-entrypoint: DDS Security with the credentials in $DPC_SECURITY_DIR" >&2
fi

if [[ -n "${FASTRTPS_DEFAULT_PROFILES_FILE:-}" ]]; then
  [[ -r "$FASTRTPS_DEFAULT_PROFILES_FILE" ]] ||
    fail "FASTRTPS_DEFAULT_PROFILES_FILE=$FASTRTPS_DEFAULT_PROFILES_FILE is not readable"
elif [[ -n "${DPC_DDS_DISCOVERY_SERVER:-}" ]]; then
  "$fastdds_dir/make_profile.sh" --discovery-server "$DPC_DDS_DISCOVERY_SERVER" >"$profile" ||
    fail "bad DPC_DDS_DISCOVERY_SERVER=$DPC_DDS_DISCOVERY_SERVER"
  echo "dpc-entrypoint: discovery server on $DPC_DDS_DISCOVERY_SERVER" >&2
  [[ $# -gt 0 && "$1" != "dpc" ]] || set -- fast-discovery-server
  exec "$@" -x "$profile"
elif [[ -n "${DPC_DDS_SERVER:-}" ]]; then
  client_profile --server DPC_DDS_SERVER "client of the discovery server $DPC_DDS_SERVER"
elif [[ -n "${DPC_DDS_PEERS:-}" ]]; then
  client_profile --peers DPC_DDS_PEERS "peers $DPC_DDS_PEERS"
fi

[[ $# -gt 0 ]] || set -- dpc --help
exec "$@"
