#!/usr/bin/env bash
# The README's test command: sets everything up (scripts/setup.sh), then runs the whole test
# suite with CTest, then fuzzes the checks at the services' edges for a bounded time
# (scripts/fuzz.sh: a clang build of its own, each target DPC_FUZZ_SECONDS, default 30 s).
# Arguments go to CTest (e.g. -R Bench); with arguments, no fuzzing.
set -euo pipefail
cd "$(dirname "$0")/.."
DPC_SETUP_TESTS=1 scripts/setup.sh
status=0
ctest --test-dir "${BUILD_DIR:-build}" --output-on-failure -j"$(nproc)" "$@" || status=$?
if [[ $status -ne 0 ]]; then
  # Fast DDS 2.9 can deadlock a secured participant (ARCHITECTURE.md: the loop guard then ends
  # the service, and its supervisor or the test starts it again), and the secured bench in
  # containers shares two cores with Docker. When the only failures are secured process tests
  # or the compose system test, they run once more; any other failure, or a second one, stands.
  failed="${BUILD_DIR:-build}/Testing/Temporary/LastTestsFailed.log"
  if [[ -s $failed ]] && ! grep -qvE ':(BenchSecurityTest\..*|compose_system)$' "$failed"; then
    echo "run-tests: only secured bench tests failed ($(cut -d: -f2 "$failed" | paste -sd ' ')): once more"
    ctest --test-dir "${BUILD_DIR:-build}" --output-on-failure --rerun-failed
  else
    exit "$status"
  fi
fi
if [[ $# -eq 0 ]]; then
  scripts/fuzz.sh --seconds "${DPC_FUZZ_SECONDS:-30}" --jobs "$(nproc)"
fi
