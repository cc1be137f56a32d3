#!/usr/bin/env bash
# Sets the project up on Debian bookworm: installs the Debian packages that are missing,
# configures and builds (Release, in ./build). Safe to run again: it only does what is missing.
#
#   scripts/setup.sh            # everything
#   DPC_SETUP_TESTS=1 scripts/setup.sh   # and what only the tests need (chromium)
#   BUILD_DIR=out/b scripts/setup.sh
set -euo pipefail
cd "$(dirname "$0")/.."

BUILD_DIR="${BUILD_DIR:-build}"
PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libboost-dev libfmt-dev libspdlog-dev libcli11-dev nlohmann-json3-dev
  libprotobuf-dev protobuf-compiler
  libgtest-dev libgmock-dev libbenchmark-dev zlib1g-dev libzstd-dev liblz4-dev
  gnuplot-nox time
  libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools
  cyclonedds-dev cyclonedds-tools iproute2 procps python3
  openssl clang libclang-rt-14-dev
)
# Node.js and npm: the dashboard's page takes three.js and uPlot from npm at build time. A machine
# that has them already (e.g. NodeSource's nodejs, which bundles npm) keeps its own.
if ! command -v npm >/dev/null; then
  PACKAGES+=(nodejs npm)
fi
# The tests drive the dashboard's page in a headless browser (scripts/run-tests.sh sets this).
if [[ "${DPC_SETUP_TESTS:-0}" == 1 ]]; then
  PACKAGES+=(chromium)
fi

missing=()
for package in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null; then
      sudo="sudo"
    else
      echo "setup: need root to install: apt-get install ${missing[*]}" >&2
      exit 1
    fi
  fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

jobs="$(nproc)"
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD_DIR" -j"$jobs"
