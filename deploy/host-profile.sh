#!/usr/bin/env bash
# Prints a Fast DDS profile for a DDS tool on the host that watches the compose bench through the
# network's gateway (the host's side of the internal bridge; nothing else is whitelisted).
#
#   deploy/host-profile.sh [--prefix 10.99.10] [--server] > /tmp/dpc-host.xml
#   FASTRTPS_DEFAULT_PROFILES_FILE=/tmp/dpc-host.xml build/tools/dpc/dpc topic echo dpc_waveplate_state
#
# --prefix: the compose file's DPC_NET_PREFIX (default: $DPC_NET_PREFIX, else 10.99.10)
# --server: the bench runs with deploy/compose/discovery-server.yml: be a client of its server
#           (default: fixed peers, the compose file's addresses)
set -euo pipefail
prefix="${DPC_NET_PREFIX:-10.99.10}"
server=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --prefix) prefix="${2:?}"; shift 2 ;;
    --server) server=1; shift ;;
    -h|--help) sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "host-profile.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ $prefix =~ ^10\.99\.[0-9]{1,3}$ ]] || { echo "host-profile.sh: --prefix must be 10.99.N (got '$prefix')" >&2; exit 2; }
make_profile="$(dirname "${BASH_SOURCE[0]}")/fastdds/make_profile.sh"
if [[ $server -eq 1 ]]; then
  exec "$make_profile" --address "$prefix.1" --server "$prefix.2:11811"
fi
exec "$make_profile" --address "$prefix.1" --peers "$prefix.10,$prefix.11,$prefix.20,$prefix.21,$prefix.30"
