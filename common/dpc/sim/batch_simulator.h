#pragma once
// Batches: several trajectories of the fast path's class simulated together, one per lane of a
// vector (4 doubles with AVX2, 8 with AVX-512), for sweeps and multi-seed runs.
//
// The lanes of a batch share the chain's stage axes, the loop delay, the sample count and the
// activation sample (CanShareBatch); each has its own seed, input, rate, law (gp / gpt / pinv),
// step sizes, target, loop mode and polarimeter noise. The control update and the plant run in
// the vector kernel (batch_kernel.h), one instruction for all lanes; the input, the polarimeters
// and the statistics stay per lane, in blocks. Every lane repeats its scalar run's operations in
// the same order, so its result equals ClosedLoopSimulator::Run's for the same scenario
// (batch_simulator_test checks every statistic of many configurations bit for bit).
//
// The kernel is compiled for each instruction set apart and chosen at run time (CPU dispatch):
// one binary uses AVX-512 where the processor has it, AVX2 elsewhere, and the scalar loop on a
// processor with neither.

#include <array>
#include <optional>
#include <span>
#include <tuple>
#include <vector>

#include "dpc/sim/closed_loop_simulator.h"

namespace dpc {

enum class BatchIsa { kNone, kAvx2, kAvx512 };

/// The widest instruction set this processor runs the kernel with.
BatchIsa DetectBatchIsa();
/// DetectBatchIsa, narrowed by the environment variable DPC_BATCH_ISA (`avx512`, `avx2` or
/// `none`) to compare the paths; never wider than the processor allows.
BatchIsa ChosenBatchIsa();
/// The lanes of a batch on `isa`: 8, 4, or 1 (no batches).
int BatchLanesOf(BatchIsa isa);
/// "avx512", "avx2", "none".
const char* BatchIsaName(BatchIsa isa);

/// What the runs of one batch have in common: the stage count and axes, the delay, the sample
/// count and the activation sample.
using BatchKey = std::tuple<int, std::array<int, 4>, int64_t, int64_t, int64_t>;
/// The simulator's key, or nullopt when it is not on the fast path (it runs alone).
std::optional<BatchKey> BatchKeyOf(const ClosedLoopSimulator& simulator);

/// Whether the two simulators' runs may be lanes of one batch: both have a BatchKeyOf, the same.
bool CanShareBatch(const ClosedLoopSimulator& a, const ClosedLoopSimulator& b);

/// What a batch computes. kAll is a run. kKernelOnly measures where a batch's time goes
/// (dpc_benchmark's BatchKernel): the kernel with its callbacks (exact poses, near-singular
/// solves, noisy polarimeters), but neither the statistics nor the update tallies; the paper
/// scrambler's normal draws of the first block are reused in every block (other inputs are
/// still generated block by block). Its results keep no statistics; their final φ is the run's
/// when the input draws nothing.
enum class BatchParts { kAll, kKernelOnly };

/// Runs the simulators (1 … BatchLanesOf(isa) of them, pairwise CanShareBatch; isa not kNone),
/// one per lane; their results in order. Each equals simulator.Run() without an observer.
/// Throws std::invalid_argument if they cannot share a batch.
std::vector<SimulationResult> RunBatch(std::span<const ClosedLoopSimulator* const> simulators,
                                       BatchIsa isa, BatchParts parts = BatchParts::kAll);

}  // namespace dpc
