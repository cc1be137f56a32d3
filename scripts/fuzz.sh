#!/usr/bin/env bash
# Fuzzes the checks at the services' edges (tests/fuzz): configures and builds the clang fuzz
# build (DPC_FUZZ=ON; only the fuzz targets and the libraries they link), then runs every
# target on a copy of its seed corpus, one after the other, and prints per target the inputs
# executed (libFuzzer's stat::number_of_executed_units), the time and the crashes.
#
#   scripts/fuzz.sh [--seconds N | --runs N] [--build-dir DIR] [--targets "a b"] [--jobs N]
#
#   --seconds N      fuzz each target for N seconds (default: 60)
#   --runs N         fuzz each target for N inputs (the benchmark: --runs 1000000)
#   --build-dir DIR  the fuzz build (default: build-fuzz; never the main build)
#   --targets "…"    only these (names without fuzz_: read_sample read_command read_state read_summary read_status
#                    read_device read_target target_request read_mcap scenario instrument_reply
#                    emulator_protocol)
#   --jobs N         build jobs (default: 1)
#
# A crash stops its target; the input is kept in DIR/tests/fuzz/artifacts/<target>/crash-* and
# the log in DIR/tests/fuzz/logs/<target>.log. Replay one with
#   DIR/tests/fuzz/fuzz_<target> DIR/tests/fuzz/artifacts/<target>/crash-…
# DPC_FUZZ_KNOWN=key,… (tests/fuzz/fuzz_support.h) tolerates findings already reported.
# Exit status: 0 if no target crashed, 1 if one did, 2 for a bad command line or build.
set -euo pipefail
cd "$(dirname "$0")/.."

mode=seconds
amount=60
build_dir=build-fuzz
jobs=1
targets="read_sample read_command read_state read_device read_target target_request read_summary read_status read_mcap scenario instrument_reply emulator_protocol"
usage() { sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//' >&2; exit "${1:-2}"; }
while (($#)); do
  case $1 in
    --seconds) mode=seconds; amount=${2:?}; shift 2 ;;
    --runs) mode=runs; amount=${2:?}; shift 2 ;;
    --build-dir) build_dir=${2:?}; shift 2 ;;
    --targets) targets=${2:?}; shift 2 ;;
    --jobs) jobs=${2:?}; shift 2 ;;
    -h|--help) usage 0 ;;
    *) echo "fuzz.sh: unknown argument $1" >&2; usage ;;
  esac
done
[[ $amount =~ ^[0-9]+$ && $amount -gt 0 ]] || { echo "fuzz.sh: --$mode needs a positive number" >&2; exit 2; }
if [[ $(realpath -m "$build_dir") == $(realpath -m build) ]]; then
  echo "fuzz.sh: $build_dir is the main build; use a build directory of its own" >&2
  exit 2
fi

echo "fuzz.sh: configuring and building $build_dir (clang, DPC_FUZZ=ON, -j$jobs)"
cmake -S . -B "$build_dir" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DDPC_FUZZ=ON -DDPC_BUILD_TESTS=OFF -DDPC_BUILD_BENCHMARKS=OFF >/dev/null || exit 2
cmake --build "$build_dir" --target dpc_fuzz -j"$jobs" || exit 2

fuzz_dir=$build_dir/tests/fuzz
mkdir -p "$fuzz_dir/logs"
if [[ $mode == runs ]]; then limit=(-runs="$amount"); else limit=(-max_total_time="$amount"); fi

status=0
summary=()
for target in $targets; do
  binary=$fuzz_dir/fuzz_$target
  [[ -x $binary ]] || { echo "fuzz.sh: no target $target ($binary)" >&2; exit 2; }
  log=$fuzz_dir/logs/$target.log
  artifacts=$fuzz_dir/artifacts/$target
  mkdir -p "$artifacts"
  before=$(find "$artifacts" -maxdepth 1 -type f \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' \) | wc -l)
  echo "fuzz.sh: fuzz_$target (${limit[*]}) → $log"
  start=$(date +%s.%N)
  rc=0
  tests/fuzz/run_fuzz_target.sh "$binary" "$fuzz_dir/seeds/$target" "$artifacts" "${limit[@]}" \
    -rss_limit_mb=2048 -timeout=20 >"$log" 2>&1 || rc=$?
  seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
  after=$(find "$artifacts" -maxdepth 1 -type f \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' \) | wc -l)
  crashes=$((after - before))
  if ((rc != 0 && crashes == 0)); then crashes=1; fi  # died without an artifact
  units=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  corpus=$(sed -n 's/^stat::new_units_added: *//p' "$log" | tail -1)
  known=$(sed -n 's/^dpc-fuzz: known finding \[\(.*\)\] tolerated \([0-9]*\) times$/\1×\2/p' "$log" | paste -sd, -)
  summary+=("$(printf '%-16s %12s %9s %9.1f %8s %7d  %s' "$target" "${units:-?}" "${rate:-?}" "$seconds" \
    "${corpus:-?}" "$crashes" "${known:--}")")
  if ((crashes > 0)); then
    status=1
    echo "fuzz.sh: fuzz_$target CRASHED (exit $rc):"
    grep -E '^dpc-fuzz: \[|^==[0-9]+==ERROR|SUMMARY:|runtime error:|Test unit written to|deadly signal|uncaught exception' "$log" | head -n 12 | sed 's/^/    /'
  fi
done

echo
printf '%-16s %12s %9s %9s %8s %7s  %s\n' target inputs exec/s seconds "new" crashes "known findings tolerated"
printf '%s\n' "${summary[@]}"
exit $status
