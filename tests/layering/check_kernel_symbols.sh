#!/bin/sh
# The batched simulator's kernel units (common/dpc/sim/batch_kernel_avx*.cc) are compiled for
# instruction sets the processor may lack. Each must define nothing but its entry point: an
# inline function or template instantiated there and defined weakly could be the copy the
# linker keeps for the whole program, and fault on a processor without AVX-512.
# Usage: check_kernel_symbols.sh FILE_LISTING_THE_OBJECTS
status=0
found=0
for object in $(cat "$1"); do
  case "$object" in
    *batch_kernel_avx*) ;;
    *) continue ;;
  esac
  found=$((found + 1))
  extra=$(nm --defined-only -g -C "$object" | grep -v ' dpc::RunBatchBlockAvx')
  if [ -n "$extra" ]; then
    echo "$object defines more than its kernel:"
    echo "$extra"
    status=1
  fi
done
if [ "$found" -ne 2 ]; then
  echo "expected the 2 kernel objects in $1, found $found"
  exit 1
fi
[ "$status" -eq 0 ] && echo "the 2 kernel objects define only their entry points"
exit $status
