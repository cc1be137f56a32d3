// The batched kernel in 8 lanes (AVX-512 F/DQ/VL; this file is compiled with -mavx512f
// -mavx512dq -mavx512vl -mfma whatever the build's baseline, and runs only where the processor
// has them). See batch_kernel.h.

#if defined(__x86_64__)
#include "dpc/sim/batch_kernel_impl.h"

namespace dpc {

void RunBatchBlockAvx512(BatchLanes& lanes, const BatchBlock& block) {
  RunBatchBlockWith<8>(lanes, block);
}

}  // namespace dpc
#endif
