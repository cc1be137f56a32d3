#!/usr/bin/env bash
# The README's main command: sets everything up (scripts/setup.sh), then runs the bench on this
# machine, loopback only: the waveplate driver, a Jacobian controller and the polarimeter (real
# time, 10 kHz) as three processes on DDS domain ${DPC_DOMAIN:-0}, on the embedded default
# scenario, with the web dashboard (http://127.0.0.1:${DPC_DASHBOARD_PORT:-8080}/) and a live
# status line until Ctrl-C. Then every process is stopped (SIGTERM, by PID) and their logs stay
# in out/bench-logs/.
#
#   scripts/run-bench.sh                              # the default bench
#   scripts/run-bench.sh deploy/scenarios/bench_default.pbtxt --rate-rad-per-s 50
#   scripts/run-bench.sh --trace out/bench.csv        # a polarimeter flag: only the polarimeter gets it
#   DPC_DOMAIN=7 DPC_DASHBOARD_PORT=8081 scripts/run-bench.sh
#   DPC_DASHBOARD=off scripts/run-bench.sh            # no dashboard
#
# A scenario file goes to all three services; each option goes to the services whose --help
# lists it (--trace and --rate-hz to the polarimeter, --priority to the controller,
# --max-slew-per-s to the driver, the scenario overrides to all), and an option none of them
# takes is refused before anything starts. A service that exits while the bench runs stops the
# bench, with the end of its log. The set-up is quiet when everything is up to date (its output
# goes to out/bench-logs/setup.log).
# While it runs, from another terminal: build/tools/dpc/dpc topic list | echo state | hz sample,
# build/tools/dpc/dpc target --point 0 0 1, or a second controller with a higher priority:
# build/services/dpc-controller --id mine --priority 10.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${BUILD_DIR:-build}"
domain="${DPC_DOMAIN:-0}"
logs=out/bench-logs
mkdir -p "$logs"

echo "run-bench.sh: setting up (scripts/setup.sh; output in $logs/setup.log) …"
if ! scripts/setup.sh >"$logs/setup.log" 2>&1; then
  tail -n 30 "$logs/setup.log" >&2
  echo "run-bench.sh: the set-up failed (the whole output: $logs/setup.log)" >&2
  exit 1
fi

services=(driver controller polarimeter)
declare -A options  # service → " --opt1 --opt2 … " (from its --help)
declare -A valued   # "--opt" → its value type (FLOAT, INT, TEXT, …) or "" for a flag
for service in "${services[@]}"; do
  help=$("$build/services/dpc-$service" --help)
  options[$service]=" $(grep -oE -- '^ +--[a-z0-9-]+' <<<"$help" | tr -d ' ' | tr '\n' ' ') "
  while read -r name type _; do
    [[ $type =~ ^[A-Z] ]] || type=""
    valued[$name]="${type%%:*}"
  done < <(grep -E -- '^ +--[a-z0-9-]+' <<<"$help" | sed 's/^ *//')
done

declare -A routed=([driver]="" [controller]="" [polarimeter]="")
add() {  # add SERVICE WORD…: appended to that service's arguments (separated by \x1f)
  local service=$1; shift
  for word in "$@"; do routed[$service]+="$word"$'\x1f'; done
}
args=("$@")
i=0
while ((i < ${#args[@]})); do
  word=${args[i]}
  i=$((i + 1))
  if [[ $word != --* ]]; then  # a scenario file: every service
    for service in "${services[@]}"; do add "$service" "$word"; done
    continue
  fi
  name=${word%%=*}
  case $name in
    --domain) echo "run-bench.sh: --domain: set DPC_DOMAIN instead (DPC_DOMAIN=$domain)" >&2; exit 2 ;;
    --id) echo "run-bench.sh: --id: the bench's controller is 'main'; start another one by hand" >&2; exit 2 ;;
  esac
  group=("$word")
  if [[ $word != *=* && -n ${valued[$name]:-} ]]; then
    # Its values: one for TEXT, every following number for numeric options (--target-point 0 0 1).
    if [[ ${valued[$name]} == TEXT ]]; then
      ((i < ${#args[@]})) && { group+=("${args[i]}"); i=$((i + 1)); }
    else
      while ((i < ${#args[@]})) && [[ ${args[i]} =~ ^[-+]?[0-9.]+([eE][-+]?[0-9]+)?$ ]]; do
        group+=("${args[i]}"); i=$((i + 1))
      done
    fi
  fi
  takers=()
  for service in "${services[@]}"; do
    [[ ${options[$service]} == *" $name "* ]] && takers+=("$service")
  done
  if ((${#takers[@]} == 0)); then
    echo "run-bench.sh: $name: no service of the bench takes this option (see build/services/dpc-driver --help, dpc-controller --help, dpc-polarimeter --help)" >&2
    exit 2
  fi
  for service in "${takers[@]}"; do add "$service" "${group[@]}"; done
done
service_args() {  # service_args SERVICE → its arguments in the array `out`
  out=()
  local rest=${routed[$1]}
  while [[ -n $rest ]]; do out+=("${rest%%$'\x1f'*}"); rest=${rest#*$'\x1f'}; done
}

pids=()
names=()
stop_all() {
  trap - EXIT INT TERM
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  echo "bench stopped; logs in $logs/"
}
trap stop_all EXIT
trap 'exit 130' INT TERM

start() {  # start NAME LOG COMMAND…
  local name=$1 log=$2; shift 2
  "$@" >"$log" 2>&1 &
  pids+=($!)
  names+=("$name")
}
service_args driver
start dpc-driver "$logs/driver.log" "$build/services/dpc-driver" --domain "$domain" "${out[@]}"
service_args controller
start dpc-controller "$logs/controller.log" "$build/services/dpc-controller" --domain "$domain" --id main "${out[@]}"
service_args polarimeter
start dpc-polarimeter "$logs/polarimeter.log" "$build/services/dpc-polarimeter" --domain "$domain" "${out[@]}"
services_count=${#pids[@]}

dashboard_port="${DPC_DASHBOARD_PORT:-8080}"
if [[ "${DPC_DASHBOARD:-on}" != off ]]; then
  "$build/tools/dpc/dpc" dashboard --domain "$domain" --port "$dashboard_port" >"$logs/dashboard.log" 2>&1 &
  dashboard_pid=$!
  pids+=("$dashboard_pid")
  sleep 0.3
  if kill -0 "$dashboard_pid" 2>/dev/null; then
    echo "dashboard: http://127.0.0.1:$dashboard_port/"
  else
    echo "run-bench.sh: the dashboard did not start ($(tail -n 1 "$logs/dashboard.log")); the bench runs without it" >&2
  fi
fi
echo "bench running on DDS domain $domain (loopback); Ctrl-C stops it"
"$build/tools/dpc/dpc" monitor --domain "$domain" &
monitor_pid=$!
pids+=("$monitor_pid")

# Watch the services: one that exits ends the bench, with why.
while kill -0 "$monitor_pid" 2>/dev/null; do
  for ((k = 0; k < services_count; k++)); do
    if ! kill -0 "${pids[k]}" 2>/dev/null; then
      status=0
      wait "${pids[k]}" || status=$?
      echo >&2
      echo "run-bench.sh: ${names[k]} exited (status $status); the end of its log ($logs/${names[k]#dpc-}.log):" >&2
      tail -n 8 "$logs/${names[k]#dpc-}.log" | sed 's/^/  /' >&2
      exit 1
    fi
  done
  sleep 0.5
done
