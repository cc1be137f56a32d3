#pragma once
// The batched simulator's vector kernel: the interface between the simulator (batch_simulator.cc,
// compiled for the build's baseline) and the kernel's builds for one instruction set each
// (batch_kernel_avx2.cc, batch_kernel_avx512.cc, chosen at run time by CPU dispatch).
//
// The kernel runs W independent trajectories of the fast path's class (PlanFusedUpdate), one per
// lane of a vector of W doubles: for each sample of a block, the plant (the command of D samples
// ago), the fused control update (control/fused_gradient_projection.h, operation for operation)
// and the delay line. Everything a lane does alone stays on the simulator's side: the input
// SOPs and the input polarimeter (generated for the block beforehand: they do not depend on the
// control), the statistics (fed after the block), and the rare cases through callbacks (a
// near-singular task, an exact re-evaluation of a pose, a noisy output polarimeter).
//
// Only plain data crosses: this header holds no code, so the kernel's translation units, built
// for instruction sets the machine may lack, define nothing another unit could pick up.

#include <cstdint>

#include "dpc/optics/rotation.h"

namespace dpc {

/// The most lanes of any kernel (AVX-512: 8 doubles); arrays below are indexed [..][lane].
inline constexpr int kMaxBatchLanes = 8;
/// The most samples per block.
inline constexpr int kBatchBlock = 64;

/// One batch's lanes: their parameters and the state carried from block to block.
struct BatchLanes {
  int width = 0;   ///< W, the kernel's lanes (4 or 8)
  int stages = 0;  ///< 3 or 4
  ElementalAxis axis[4] = {};
  bool paper_axes = false;  ///< R1R3R1 or R1R3R1R3 (compile-time axes)
  int64_t delay_samples = 1;
  int64_t activation_sample = 0;
  /// The scalar build's arithmetic and constants, so that a lane repeats its operations:
  /// whether MulAdd is one fused multiply-add (kMulAddIsFused as the baseline build sees it),
  /// FusedGradientProjection's det G threshold, the pose's updates by angle addition between
  /// exact evaluations.
  bool fused_multiply_add = false;
  double well_conditioned = 0.0;
  int64_t max_incremental_steps = 0;

  // Per lane: the fused update's plan (FusedUpdatePlan).
  double rad_per_unit[4][kMaxBatchLanes] = {};
  double step[kMaxBatchLanes] = {};
  double nullspace_step[kMaxBatchLanes] = {};
  double threshold[kMaxBatchLanes] = {};
  double target[3][kMaxBatchLanes] = {};
  bool has_threshold[kMaxBatchLanes] = {};
  bool measured_loop[kMaxBatchLanes] = {};
  bool noisy_output[kMaxBatchLanes] = {};  ///< the output polarimeter has noise (callback)

  // State: the controller's command (its pose) and updates by angle addition since its exact
  // evaluation; the delay line (D slots of φ, cos, sin: line[((slot·3 + q)·4 + stage)·8 + lane],
  // q = 0 φ, 1 cos, 2 sin) and the slot of the next sample.
  double phi[4][kMaxBatchLanes] = {};
  double cos[4][kMaxBatchLanes] = {};
  double sin[4][kMaxBatchLanes] = {};
  int incremental_steps[kMaxBatchLanes] = {};
  double* line = nullptr;
  int64_t slot = 0;

  // The input, when every lane's is the paper scrambler alone with elemental axes, the same in
  // every lane (vector_input; PaperScrambler::Advance lane by lane with the block's normal
  // draws): the SOP of the last sample, the step's cos and sin, the kick's σ (0: no kick).
  bool vector_input = false;
  ElementalAxis input_rotation_axis = ElementalAxis::kS3;
  ElementalAxis input_kick_axis = ElementalAxis::kS2;
  double sop[3][kMaxBatchLanes] = {};
  double input_step_cos[kMaxBatchLanes] = {};
  double input_step_sin[kMaxBatchLanes] = {};
  double input_kick_sigma[kMaxBatchLanes] = {};
  bool noisy_input[kMaxBatchLanes] = {};  ///< the input polarimeter has noise (callback)

  // The simulator's side, for one lane at a time.
  void* context = nullptr;
  /// FusedGradientProjection::SolveNearSingularity for `lane` at the block's sample `index`:
  /// fills delta[0 … stages), keeps the singular values itself, returns the rank.
  int (*near_singular)(void* context, int lane, int index, const double* t0, const double* t1,
                       double error0, double error1, const double* phi, double mu_null,
                       double* delta) = nullptr;
  /// FusedGradientProjection::ExactPose for `lane`: cos and sin of its stages at phi.
  void (*exact_pose)(void* context, int lane, const double* phi, double* cos,
                     double* sin) = nullptr;
  /// The output polarimeter's reading of `s_out` for `lane` (only lanes with noisy_output).
  void (*measure_output)(void* context, int lane, const double* s_out, double* measured) = nullptr;
  /// The input polarimeter's reading (vector_input, lanes with noisy_input).
  void (*measure_input)(void* context, int lane, const double* s_in, double* measured) = nullptr;
  /// SinCos (rotation.h) of the scalar build, for a kick beyond the small-angle series.
  void (*sin_cos)(double x, double* s, double* c) = nullptr;
};

/// Update outcomes in BatchBlock::flags.
enum BatchUpdateFlag : uint8_t {
  kBatchUpdated = 1,          ///< an update ran (the sample is at or after activation)
  kBatchApplied = 2,          ///< Δφ was finite
  kBatchNullspaceActive = 4,  ///< the null-space term ran
  kBatchNearSingular = 8,     ///< solved by near_singular (rank and σ are the callback's)
};

/// One block of samples, laid out [quantity][index·8 + lane].
struct BatchBlock {
  int64_t first_sample = 0;
  int count = 0;  ///< ≤ kBatchBlock
  const double* s_in[3] = {};         ///< the input SOPs (unless vector_input)
  const double* measured_in[3] = {};  ///< the input polarimeter's readings (unless vector_input)
  const double* normals = nullptr;    ///< vector_input: the kicks' normal draws (σ > 0, k ≥ 1)
  double* s_out[3] = {};              ///< written: the true output
  double* phi_applied[4] = {};        ///< written: the command the plant applied
  uint8_t* flags = nullptr;           ///< written: BatchUpdateFlag per sample and lane
  double* gram[4] = {};               ///< written: g11, g22, g12, det G of well-conditioned updates
};

/// The kernels, one per instruction set (defined only where the compiler can build them).
void RunBatchBlockAvx2(BatchLanes& lanes, const BatchBlock& block);
void RunBatchBlockAvx512(BatchLanes& lanes, const BatchBlock& block);

}  // namespace dpc
