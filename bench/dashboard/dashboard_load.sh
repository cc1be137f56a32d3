#!/usr/bin/env bash
# What the dashboard costs a running bench, measured: rounds of three runs, alternated so that
# the machine's drift falls on all of them alike —
#   alone      driver + controller + polarimeter (real time)
#   dashboard  the same with `dpc dashboard` subscribed (no page open)
#   page       the same with the page open in headless chromium (SwiftShader WebGL)
# Each run: the polarimeter's loop latency (sample → state received, p50/p99), its achieved rate,
# the dashboard's CPU share (of one core) and the page's frame rate. Loopback only, domain 93,
# bounded by --seconds per run.
#
#   bench/dashboard/dashboard_load.sh [--build build] [--rate-hz 10000] [--seconds 10] [--rounds 3]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$here/../../build
rate=10000
seconds=10
rounds=3
domain=93
while (($#)); do
  case $1 in
    --build) build=$2; shift 2 ;;
    --rate-hz) rate=$2; shift 2 ;;
    --seconds) seconds=$2; shift 2 ;;
    --rounds) rounds=$2; shift 2 ;;
    *) echo "dashboard_load.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
modules=$build/tests/dashboard-npm/node_modules
port=18093
tmp=$(mktemp -d /tmp/dpc-dashboard-load.XXXXXX)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  [[ -n ${DPC_KEEP_TMP:-} ]] || rm -rf "$tmp"
}
trap cleanup EXIT

cpu_ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }

run() {  # run MODE ROUND → one line of figures
  local mode=$1 round=$2
  pids=()
  "$build/services/dpc-driver" --domain $domain >"$tmp/driver.log" 2>&1 & pids+=($!)
  "$build/services/dpc-controller" --domain $domain --id main >"$tmp/controller.log" 2>&1 & pids+=($!)
  local dashboard_pid="" page_pid=""
  if [[ $mode != alone ]]; then
    "$build/tools/dpc/dpc" dashboard --domain $domain --port $port >"$tmp/dashboard.log" 2>&1 &
    dashboard_pid=$!; pids+=("$dashboard_pid")
  fi
  sleep 1
  if [[ $mode == page ]]; then
    node "$here/page_fps.mjs" --url "http://127.0.0.1:$port/" --seconds "$((seconds - 3))" --modules "$modules" \
      >"$tmp/page.json" 2>"$tmp/page.log" &
    page_pid=$!
  fi
  local ticks0=0
  [[ -n $dashboard_pid ]] && ticks0=$(cpu_ticks "$dashboard_pid")
  "$build/services/dpc-polarimeter" --domain $domain --rate-hz "$rate" --run-s "$seconds" --settle-s 2 --json \
    >"$tmp/bench.json" 2>"$tmp/polarimeter.log"
  local cpu="-"
  if [[ -n $dashboard_pid ]]; then
    cpu=$(awk -v a="$ticks0" -v b="$(cpu_ticks "$dashboard_pid")" -v hz="$(getconf CLK_TCK)" -v s="$seconds" \
      'BEGIN { printf "%.1f", 100 * (b - a) / hz / s }')
  fi
  local fps="-"
  if [[ -n $page_pid ]]; then
    wait "$page_pid" || true
    fps=$(python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print("%.1f (%.1f draws/s)" % (d["frames_per_s"], d["draws_per_s"]))' "$tmp/page.json" 2>/dev/null || echo "failed: $(tail -n 1 "$tmp/page.log")")
  fi
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  pids=()
  python3 - "$tmp/bench.json" "$mode" "$round" "$cpu" "$fps" <<'EOF'
import json, sys
bench = json.load(open(sys.argv[1]))["bench"]
latency = bench["loop_latency_us"]["sample_to_state_received"]
print(f"round {sys.argv[3]}  {sys.argv[2]:<9}  achieved {bench['achieved_rate_hz']:7.0f} Hz  "
      f"loop p50 {latency['p50']:7.1f} us  p99 {latency['p99']:8.1f} us  "
      f"dashboard CPU {sys.argv[4]:>5} %  page {sys.argv[5]} fps")
EOF
}

echo "dashboard load: bench at $rate Hz, $seconds s per run, $rounds rounds ($(nproc) CPUs, $(uname -r))"
for ((r = 1; r <= rounds; r++)); do
  for mode in alone dashboard page; do run "$mode" "$r"; done
done
