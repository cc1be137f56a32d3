#!/usr/bin/env bash
# The README's main command: sets everything up (scripts/setup.sh), then runs the bench on this
# machine, loopback only: the waveplate driver, a Jacobian controller and the polarimeter (real
# time, 10 kHz) as three processes on DDS domain ${DPC_DOMAIN:-0}, on the embedded default
# scenario, with a live status line (error, φ, sample rate, obeyed controller) until Ctrl-C.
# Then every process is stopped (SIGTERM, by PID) and their logs stay in out/bench-logs/.
#
#   scripts/run-bench.sh                              # the default bench
#   scripts/run-bench.sh deploy/scenarios/bench_default.pbtxt --rate-rad-per-s 50
#   DPC_DOMAIN=7 scripts/run-bench.sh
#
# Arguments go to all three services (a scenario file and the `dpc sim` override flags).
# While it runs, from another terminal: build/tools/dpc/dpc topic list | echo state | hz sample,
# build/tools/dpc/dpc target --point 0 0 1, or a second controller with a higher priority:
# build/services/dpc-controller --id mine --priority 10.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
build="${BUILD_DIR:-build}"
domain="${DPC_DOMAIN:-0}"
logs=out/bench-logs
mkdir -p "$logs"

pids=()
stop_all() {
  trap - EXIT INT TERM
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  echo "bench stopped; logs in $logs/"
}
trap stop_all EXIT
trap 'exit 130' INT TERM

"$build/services/dpc-driver" --domain "$domain" "$@" >"$logs/driver.log" 2>&1 &
pids+=($!)
"$build/services/dpc-controller" --domain "$domain" --id main "$@" >"$logs/controller.log" 2>&1 &
pids+=($!)
"$build/services/dpc-polarimeter" --domain "$domain" "$@" >"$logs/polarimeter.log" 2>&1 &
pids+=($!)
echo "bench running on DDS domain $domain (loopback); Ctrl-C stops it"
"$build/tools/dpc/dpc" monitor --domain "$domain" || true
