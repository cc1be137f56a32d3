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
#                                    transport is whitelisted to it and nothing else
# With none of them, the services use their compiled-in loopback profile (this container only).
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

# client_profile OPTION VARIABLE DESCRIPTION: this container's profile from make_profile.sh
# --address <own address> OPTION "${!VARIABLE}", used by every participant the command starts.
client_profile() {
  local address
  address=$(own_address)
  "$fastdds_dir/make_profile.sh" --address "$address" "$1" "${!2}" >"$profile" ||
    fail "bad $2=${!2} or DPC_DDS_ADDRESS=$address"
  export FASTRTPS_DEFAULT_PROFILES_FILE="$profile"
  echo "dpc-entrypoint: UDPv4 on $address, $3" >&2
}

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
