#!/usr/bin/env bash
# `cmake --install` of the build into a fresh prefix, then: every installed program answers
# --version and finds its data there (the loopback profile, the scenarios, the dashboard's
# page), bash completion completes dpc's commands, and a consumer project (tests/install/consumer)
# builds against find_package(jacobian_dpc) and runs the paper's scenario with the core library.
#
#   install_test.sh BUILD_DIR
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$(cd "$1" && pwd)
work=$(mktemp -d /tmp/dpc-install-test.XXXXXX)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
prefix=$work/prefix

cmake --install "$build" --prefix "$prefix" >"$work/install.log" || { cat "$work/install.log"; fail "cmake --install"; }
for f in bin/dpc bin/dpc-driver bin/dpc-controller bin/dpc-polarimeter bin/dpc-emulator share/dpc/fastdds/loopback.xml \
         share/dpc/fastdds/make_profile.sh share/dpc/scenarios/paper_fig3.pbtxt \
         share/dpc/scenarios/emulator_epc.pbtxt share/dpc/idl/dpc/bench.idl \
         share/dpc/security/make-bench-pki.sh share/bash-completion/completions/dpc \
         include/dpc/optics/waveplate_chain.h include/dpc/sim/closed_loop_simulator.h \
         lib/cmake/jacobian_dpc/jacobian_dpcConfig.cmake lib/cmake/jacobian_dpc/jacobian_dpcConfigVersion.cmake; do
  [[ -e $prefix/$f ]] || fail "$f not installed"
done
echo "installed into $prefix: $(find "$prefix" -type f | wc -l) files"
for program in dpc dpc-driver dpc-controller dpc-polarimeter dpc-emulator; do
  version=$("$prefix/bin/$program" --version) || fail "$program --version"
  [[ $version == *"Fast DDS"* ]] || fail "$program --version: $version"
done
echo "--version: $version"
# The installed dpc simulates an installed scenario.
"$prefix/bin/dpc" sim "$prefix/share/dpc/scenarios/paper_fig3.pbtxt" --duration-s 3e-3 --json >"$work/sim.json" ||
  fail "installed dpc sim on an installed scenario"
# It finds its page where it was installed (not in the build tree).
if [[ -e $build/share/dpc/dashboard/index.html ]]; then
  [[ -e $prefix/share/dpc/dashboard/index.html && -e $prefix/share/dpc/dashboard/vendor/three/three.module.js ]] ||
    fail "the dashboard's page not installed"
fi

# Bash completion of the installed dpc.
completion=$(bash -c '
  source "$1/share/bash-completion/completions/dpc"
  COMP_WORDS=("$1/bin/dpc" sim --met); COMP_CWORD=2; _dpc; echo "${COMPREPLY[*]}"
  COMP_WORDS=("$1/bin/dpc" dash); COMP_CWORD=1; _dpc; echo "${COMPREPLY[*]}"
  COMP_WORDS=("$1/bin/dpc" topic echo st); COMP_CWORD=3; _dpc; echo "${COMPREPLY[*]}"' _ "$prefix")
[[ $completion == $'--method\ndashboard\nstate status' ]] || fail "bash completion gave: $completion"
echo "bash completion: dpc sim --met → --method, dpc dash → dashboard, dpc topic echo st → state status"

# Someone else's project against the package.
cmake -S "$here/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release \
  >"$work/consumer-configure.log" 2>&1 || { cat "$work/consumer-configure.log"; fail "consumer configure"; }
cmake --build "$work/consumer" -j2 >"$work/consumer-build.log" 2>&1 || { tail -n 30 "$work/consumer-build.log"; fail "consumer build"; }
output=$("$work/consumer/dpc_consumer") || fail "consumer run: $output"
echo "consumer (find_package(jacobian_dpc), jacobian_dpc::core): $output"
echo PASS
