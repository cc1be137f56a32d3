// The batched kernel in 4 lanes (AVX2 and FMA; this file is compiled with -mavx2 -mfma whatever
// the build's baseline). See batch_kernel.h.

#if defined(__x86_64__)
#include "dpc/sim/batch_kernel_impl.h"

namespace dpc {

void RunBatchBlockAvx2(BatchLanes& lanes, const BatchBlock& block) {
  RunBatchBlockWith<4>(lanes, block);
}

}  // namespace dpc
#endif
