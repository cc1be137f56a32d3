#!/usr/bin/env bash
# Runs a `dpc` DDS tool on the host against the compose bench, through the network's gateway:
# waits until the bench's bridge is up (Fast DDS drops a whitelisted address whose interface is
# down, and the bridge comes up only when the first container attaches), writes the host profile
# (deploy/host-profile.sh) and runs the tool with it.
#
#   deploy/host-dpc.sh                           # dpc monitor
#   deploy/host-dpc.sh topic echo state --json   # any dpc command
#   DPC_NET_PREFIX=10.99.12 deploy/host-dpc.sh … # another compose network
#   DPC_HOST_PROFILE_ARGS=--server deploy/host-dpc.sh …   # with deploy/compose/discovery-server.yml
# The tool: DPC_BINARY if set, else the host build (build/tools/dpc/dpc) if there is one, else
# `dpc` from the bench's image (DPC_IMAGE, dpc-bench:latest, which `docker-compose up` built), run
# in the host's network namespace with the same profile: no host build needed. DPC_RUN=image
# forces the image. DPC_WAIT_S: how long to wait for the bench's network (60 s).
# DDS Security: the compose bench's tools credentials ($DPC_PKI_DIR/bench/tools, by default
# ./deploy/security/compose-pki/bench/tools: the observer, and the operator for `dpc target`;
# made by its pki service, owned by the image's user 10001: run as root or that user) are used
# when they exist, unless DPC_SECURITY=off.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
prefix="${DPC_NET_PREFIX:-10.99.10}"
dpc="${DPC_BINARY:-$here/../build/tools/dpc/dpc}"
image="${DPC_IMAGE:-dpc-bench:latest}"
use_image=0
if [[ "${DPC_RUN:-}" == image || ( -z "${DPC_BINARY:-}" && ! -x "$dpc" ) ]]; then
  docker image inspect "$image" >/dev/null 2>&1 || {
    echo "host-dpc.sh: neither a host build ($dpc) nor the image $image: \`docker-compose build\` makes the image (scripts/setup.sh the host build)" >&2
    exit 2
  }
  use_image=1
fi
[[ $use_image -eq 1 || -x "$dpc" ]] || { echo "host-dpc.sh: $dpc is not executable" >&2; exit 2; }
[[ $# -gt 0 ]] || set -- monitor
pki="${DPC_PKI_DIR:-$here/security/compose-pki}/bench/tools"
if [[ "${DPC_SECURITY:-on}" != "off" && -z "${DPC_SECURITY_DIR:-}" && -e "$pki/ready" ]]; then
  export DPC_SECURITY_DIR="$pki"
fi

deadline=$((SECONDS + ${DPC_WAIT_S:-60}))
announced=0
until ip -o -4 addr show up 2>/dev/null | grep -q " inet $prefix\.1/" &&
      ip -o link show "$(ip -o -4 addr | awk -v a="$prefix.1/" 'index($4, a) == 1 {print $2}')" 2>/dev/null |
        grep -q 'state UP'; do
  if ((SECONDS >= deadline)); then
    echo "host-dpc.sh: no bench network with gateway $prefix.1 is up (is \`docker-compose up\` running?)" >&2
    exit 3
  fi
  ((announced)) || { echo "host-dpc.sh: waiting for the bench's network ($prefix.0/24) …" >&2; announced=1; }
  sleep 0.2
done

profile=$(mktemp /tmp/dpc-host-profile.XXXXXX.xml)
trap 'rm -f "$profile"' EXIT
# shellcheck disable=SC2086
"$here/host-profile.sh" --prefix "$prefix" ${DPC_HOST_PROFILE_ARGS:-} >"$profile"
if [[ $use_image -eq 1 ]]; then
  # The image's user (10001) reads the profile (no secret in it) and the tools' credentials
  # (made for that user by the pki service); the root file system stays read-only.
  chmod 644 "$profile"
  run=(docker run --rm -i --network host --read-only --tmpfs /tmp
       -v "$profile:/etc/dpc-host-profile.xml:ro" -e FASTRTPS_DEFAULT_PROFILES_FILE=/etc/dpc-host-profile.xml)
  [[ ! -t 0 || ! -t 1 ]] || run+=(-t)
  if [[ -n "${DPC_SECURITY_DIR:-}" ]]; then
    run+=(-v "$(cd "$DPC_SECURITY_DIR" && pwd):/pki:ro" -e DPC_SECURITY_DIR=/pki -e DPC_SECURITY_WAIT_S=0)
  fi
  [[ -z "${DPC_IDENTITY:-}" ]] || run+=(-e "DPC_IDENTITY=$DPC_IDENTITY")
  "${run[@]}" "$image" dpc "$@" &
else
  FASTRTPS_DEFAULT_PROFILES_FILE="$profile" "$dpc" "$@" &
fi
child=$!
trap 'kill -TERM $child 2>/dev/null || true' INT TERM
wait $child || status=$?
wait $child 2>/dev/null || true
exit "${status:-0}"
