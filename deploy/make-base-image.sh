#!/usr/bin/env bash
# Builds the base image debian:bookworm-slim locally (debootstrap + docker import), for machines
# where it cannot be pulled (no container registry reachable). The Dockerfile's
# `FROM ${BASE_IMAGE}` then builds unchanged.
#
# Usage: deploy/make-base-image.sh [--force] [--tag NAME] [--mirror URL]
#   --force   rebuild even when the tag already exists
#   --tag     image name to create (default debian:bookworm-slim)
#   --mirror  Debian mirror (default: the first one apt on this machine uses, else deb.debian.org)
# Needs root, debootstrap and a running Docker engine. Takes about a minute.
set -euo pipefail

tag="debian:bookworm-slim"
force=0
mirror="${DEBIAN_MIRROR:-}"
while [[ $# -gt 0 ]]; do
  case "$1" in
    --force) force=1; shift ;;
    --tag) tag="$2"; shift 2 ;;
    --mirror) mirror="$2"; shift 2 ;;
    -h|--help) sed -n '2,10p' "$0"; exit 0 ;;
    *) echo "make-base-image: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

if [[ $force -eq 0 ]] && docker image inspect "$tag" >/dev/null 2>&1; then
  echo "make-base-image: $tag already present; nothing to do (--force rebuilds it)"
  exit 0
fi
if [[ $(id -u) -ne 0 ]]; then
  echo "make-base-image: debootstrap needs root; run it with sudo" >&2
  exit 1
fi
command -v debootstrap >/dev/null || { echo "make-base-image: debootstrap missing (apt-get install debootstrap)" >&2; exit 1; }

if [[ -z "$mirror" ]]; then
  # The mirror apt already reaches: deb822 "URIs:" lines first, then one-line sources.
  mirror=$(grep -hs '^URIs:' /etc/apt/sources.list.d/debian.sources | awk '{print $2}' | grep -v security | head -1 || true)
  [[ -z "$mirror" ]] && mirror=$(grep -hsE '^deb ' /etc/apt/sources.list | awk '{print $2}' | grep -v security | head -1 || true)
  [[ -z "$mirror" ]] && mirror="http://deb.debian.org/debian"
fi
security_mirror="${mirror%/debian}/debian-security"

root=$(mktemp -d /tmp/dpc-base-rootfs.XXXXXX)
trap 'rm -rf "$root"' EXIT
echo "make-base-image: debootstrap bookworm (minbase) from $mirror into $root"
debootstrap --variant=minbase bookworm "$root" "$mirror" >"$root.log" 2>&1 || {
  echo "make-base-image: debootstrap failed; last lines of $root.log:" >&2
  tail -20 "$root.log" >&2
  exit 1
}
rm -f "$root.log"

# The same apt sources as the official image (main, updates, security), and its slimming:
# no package lists, no caches, no docs or man pages left from the bootstrap.
rm -f "$root/etc/apt/sources.list"
cat >"$root/etc/apt/sources.list.d/debian.sources" <<SOURCES
Types: deb
URIs: $mirror
Suites: bookworm bookworm-updates
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg

Types: deb
URIs: $security_mirror
Suites: bookworm-security
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
SOURCES
cat >"$root/etc/dpkg/dpkg.cfg.d/docker-slim" <<'SLIM'
path-exclude /usr/share/doc/*
path-include /usr/share/doc/*/copyright
path-exclude /usr/share/man/*
path-exclude /usr/share/info/*
path-exclude /usr/share/locale/*
SLIM
cat >"$root/etc/apt/apt.conf.d/docker-clean" <<'CLEAN'
DPkg::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/archives/partial/*.deb /var/cache/apt/*.bin || true"; };
APT::Update::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/archives/partial/*.deb /var/cache/apt/*.bin || true"; };
Dir::Cache::pkgcache ""; Dir::Cache::srcpkgcache "";
CLEAN
echo 'APT::Install-Recommends "false";' >"$root/etc/apt/apt.conf.d/docker-no-recommends"
rm -rf "$root"/var/lib/apt/lists/* "$root"/var/cache/apt/*.bin "$root"/var/cache/apt/archives/*.deb \
       "$root"/usr/share/info/* "$root"/var/log/*.log "$root"/tmp/*
find "$root/usr/share/man" -not -type d -delete 2>/dev/null || true  # (keep the dirs: openjdk needs man1)
find "$root/usr/share/locale" -mindepth 1 -maxdepth 1 -not -name locale.alias -exec rm -rf {} + 2>/dev/null || true
find "$root/usr/share/doc" -mindepth 2 -not -name copyright -not -type d -delete 2>/dev/null || true

echo "make-base-image: importing as $tag"
tar --numeric-owner -C "$root" -c . |
  docker import --change 'CMD ["bash"]' \
    --change 'LABEL org.opencontainers.image.description="debian bookworm minbase, built locally by deploy/make-base-image.sh"' \
    - "$tag" >/dev/null
docker image ls "$tag"
