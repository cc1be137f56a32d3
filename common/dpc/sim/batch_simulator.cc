#include "dpc/sim/batch_simulator.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string_view>

#include "dpc/control/fused_gradient_projection.h"
#include "dpc/disturbance/paper_scrambler.h"
#include "dpc/sim/batch_kernel.h"
#include "dpc/sim/simulation_run.h"

namespace dpc {

BatchIsa DetectBatchIsa() {
#if defined(__x86_64__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
      __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("fma")) {
    return BatchIsa::kAvx512;
  }
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return BatchIsa::kAvx2;
#endif
  return BatchIsa::kNone;
}

BatchIsa ChosenBatchIsa() {
  const BatchIsa detected = DetectBatchIsa();
  const char* chosen = std::getenv("DPC_BATCH_ISA");
  if (chosen == nullptr) return detected;
  const std::string_view name(chosen);
  BatchIsa wanted = detected;
  if (name == "none") wanted = BatchIsa::kNone;
  if (name == "avx2") wanted = BatchIsa::kAvx2;
  if (name == "avx512") wanted = BatchIsa::kAvx512;
  return std::min(wanted, detected);
}

int BatchLanesOf(BatchIsa isa) {
  switch (isa) {
    case BatchIsa::kAvx512: return 8;
    case BatchIsa::kAvx2: return 4;
    case BatchIsa::kNone: return 1;
  }
  return 1;
}

const char* BatchIsaName(BatchIsa isa) {
  switch (isa) {
    case BatchIsa::kAvx512: return "avx512";
    case BatchIsa::kAvx2: return "avx2";
    case BatchIsa::kNone: return "none";
  }
  return "none";
}

std::optional<BatchKey> BatchKeyOf(const ClosedLoopSimulator& simulator) {
  const std::optional<FusedUpdatePlan>& plan = simulator.fast_path_plan();
  if (!plan) return std::nullopt;
  std::array<int, 4> axes = {-1, -1, -1, -1};
  for (int e = 0; e < plan->stages; ++e) axes[static_cast<size_t>(e)] = static_cast<int>(plan->axis[e]);
  return BatchKey{plan->stages, axes, simulator.delay_samples(), simulator.total_samples(),
                  simulator.activation_sample()};
}

bool CanShareBatch(const ClosedLoopSimulator& a, const ClosedLoopSimulator& b) {
  const std::optional<BatchKey> key = BatchKeyOf(a);
  return key.has_value() && key == BatchKeyOf(b);
}

namespace {

/// What a lane keeps on the scalar side: its run (input, polarimeters, statistics) and its
/// scalar update (for the near-singular solve and the exact poses), with the near-singular
/// outcomes of the current block.
template <typename Axes>
struct Lane {
  Lane(const ClosedLoopSimulator& simulator, const Axes& axes)
      : simulator(simulator),
        run(simulator.scenario(), simulator.target(), Axes::kStages, simulator.total_samples(),
            nullptr, 1),
        update(*simulator.fast_path_plan(), axes),
        sample_period_s(1.0 / simulator.scenario().simulation.sample_rate_hz) {}

  const ClosedLoopSimulator& simulator;
  SimulationRun run;
  FusedGradientProjection<Axes> update;
  double sample_period_s;
  int rank[kBatchBlock] = {};
  SingularValues singular_values[kBatchBlock];
};

template <typename Axes>
struct Batch {
  std::vector<std::unique_ptr<Lane<Axes>>> lanes;  ///< the real lanes; the rest repeat lane 0
  bool Real(int lane) const { return lane < static_cast<int>(lanes.size()); }
};

template <typename Axes>
int NearSingular(void* context, int lane, int index, const double* t0, const double* t1,
                 double error0, double error1, const double* phi, double mu_null, double* delta) {
  auto& batch = *static_cast<Batch<Axes>*>(context);
  if (!batch.Real(lane)) {  // a padding lane: its outcome is discarded
    for (int e = 0; e < Axes::kStages; ++e) delta[e] = 0.0;
    return 2;
  }
  Lane<Axes>& l = *batch.lanes[static_cast<size_t>(lane)];
  const Lanes row0 = {t0[0], t0[1], t0[2], t0[3]}, row1 = {t1[0], t1[1], t1[2], t1[3]};
  const Lanes phi_lanes = {phi[0], phi[1], phi[2], phi[3]};
  Lanes delta_lanes;
  const int rank = l.update.SolveNearSingularity(row0, row1, error0, error1, phi_lanes, mu_null,
                                                 &delta_lanes, &l.singular_values[index]);
  l.rank[index] = rank;
  for (int e = 0; e < Axes::kStages; ++e) delta[e] = delta_lanes[e];
  return rank;
}

template <typename Axes>
void ExactPose(void* context, int lane, const double* phi, double* cos, double* sin) {
  auto& batch = *static_cast<Batch<Axes>*>(context);
  const Lane<Axes>& l = *batch.lanes[batch.Real(lane) ? static_cast<size_t>(lane) : 0];
  ElementalPose<Axes::kStages> pose;
  for (int e = 0; e < Axes::kStages; ++e) pose.phi[e] = phi[e];
  l.update.ExactPose(&pose);
  for (int e = 0; e < Axes::kStages; ++e) cos[e] = pose.cos[e], sin[e] = pose.sin[e];
}

template <typename Axes>
void MeasureOutput(void* context, int lane, const double* s_out, double* measured) {
  auto& batch = *static_cast<Batch<Axes>*>(context);
  if (!batch.Real(lane)) {
    for (int c = 0; c < 3; ++c) measured[c] = s_out[c];
    return;
  }
  const StokesVector m = batch.lanes[static_cast<size_t>(lane)]->run.output_polarimeter.Measure(
      StokesVector(s_out[0], s_out[1], s_out[2]));
  for (int c = 0; c < 3; ++c) measured[c] = m[c];
}

template <typename Axes>
void MeasureInput(void* context, int lane, const double* s_in, double* measured) {
  auto& batch = *static_cast<Batch<Axes>*>(context);
  const StokesVector m = batch.lanes[static_cast<size_t>(lane)]->run.input_polarimeter.Measure(
      StokesVector(s_in[0], s_in[1], s_in[2]));
  for (int c = 0; c < 3; ++c) measured[c] = m[c];
}

void LibrarySinCos(double x, double* s, double* c) { SinCos(x, s, c); }

/// Whether every lane's input is the paper scrambler alone with elemental axes, the same in
/// every lane: the kernel then runs it (BatchLanes::vector_input).
template <typename Axes>
bool VectorInput(const Batch<Axes>& batch) {
  const PaperScrambler* first = batch.lanes[0]->run.input.only_scrambler();
  if (first == nullptr || first->rotation_elemental() == ElementalAxis::kGeneral ||
      first->kick_elemental() == ElementalAxis::kGeneral) {
    return false;
  }
  for (const auto& lane : batch.lanes) {
    const PaperScrambler* scrambler = lane->run.input.only_scrambler();
    if (scrambler == nullptr || scrambler->rotation_elemental() != first->rotation_elemental() ||
        scrambler->kick_elemental() != first->kick_elemental()) {
      return false;
    }
  }
  return true;
}

/// A block's buffers, [quantity][index·8 + lane].
struct BlockBuffers {
  static constexpr size_t kSize = static_cast<size_t>(kBatchBlock) * kMaxBatchLanes;
  alignas(64) double s_in[3][kSize];
  alignas(64) double measured_in[3][kSize];
  alignas(64) double s_out[3][kSize];
  alignas(64) double phi_applied[4][kSize];
  alignas(64) double gram[4][kSize];
  alignas(64) double normals[kSize];
  alignas(64) uint8_t flags[kSize];
};

/// The updates' statistics of a batch's lanes (UpdateTally), tallied sample by sample with one
/// vector operation for four lanes (each lane's in its sample order, as RunStatistics::AddUpdate
/// counts them); the near-singular lanes' singular values, and the candidates for a new
/// smallest σ_min, lane by lane.
class LaneUpdateTallies {
 public:
  static constexpr int kWidth = 4;  ///< lanes per vector (AVX2, the baseline build's)
  using V = double __attribute__((vector_size(8 * kWidth)));
  using M = int64_t __attribute__((vector_size(8 * kWidth)));

  /// The block's samples [first, count) of the lanes below `real`; lane_of(l) gives lane l
  /// (its rank and singular values of near-singular samples).
  template <typename LaneOf>
  void Add(const BlockBuffers& buffers, int first, int count, LaneOf&& lane_of, int real) {
    updates_ += count - first;
    for (int h = 0; h * kWidth < real; ++h) {
      Half& half = halves_[h];
      for (int i = first; i < count; ++i) {
        const size_t at = static_cast<size_t>(i) * kMaxBatchLanes + static_cast<size_t>(h) * kWidth;
        M flags;
        for (int l = 0; l < kWidth; ++l) flags[l] = buffers.flags[at + static_cast<size_t>(l)];
        const M near = (flags & int64_t{kBatchNearSingular}) != 0;
        half.nullspace_active -= (flags & int64_t{kBatchNullspaceActive}) != 0;  // a set mask is −1
        half.failed -= (flags & int64_t{kBatchApplied}) == 0;
        V g11, g22, det;
        std::memcpy(&g11, buffers.gram[0] + at, sizeof(V));
        std::memcpy(&g22, buffers.gram[1] + at, sizeof(V));
        std::memcpy(&det, buffers.gram[3] + at, sizeof(V));
        half.near_singular -=
            SingularValues::GramIsBelowRatio(g11, g22, det, UpdateTally::kNearSingularRatio) & ~near;
        const M candidate =
            SingularValues::GramMayBeBelow(g11, g22, det, half.min_sigma_squared) & ~near;
        const M rare = candidate | near;
        if ((rare[0] | rare[1] | rare[2] | rare[3]) == 0) continue;
        for (int l = 0; l < kWidth && h * kWidth + l < real; ++l) {
          if (candidate[l] != 0) {
            const double squared = SingularValues::FromGram(g11[l], g22[l],
                                                            buffers.gram[2][at + static_cast<size_t>(l)],
                                                            det[l]).min_squared();
            half.min_sigma_squared[l] = std::min(half.min_sigma_squared[l], squared);
          } else if (near[l] != 0) {
            const auto& lane = lane_of(h * kWidth + l);
            UpdateTally tally;
            tally.min_sigma_squared = half.min_sigma_squared[l];
            tally.AddSingularValues(lane.singular_values[i]);
            half.min_sigma_squared[l] = tally.min_sigma_squared;
            half.near_singular[l] += tally.near_singular;
            half.rank_deficient[l] += (flags[l] & int64_t{kBatchApplied}) != 0 && lane.rank[i] < 2;
          }
        }
      }
    }
  }

  /// Lane l's tally.
  UpdateTally Lane(int l) const {
    const Half& half = halves_[l / kWidth];
    const int in = l % kWidth;
    UpdateTally tally;
    tally.updates = updates_;
    tally.nullspace_active = half.nullspace_active[in];
    tally.failed = half.failed[in];
    tally.rank_deficient = half.rank_deficient[in];
    tally.near_singular = half.near_singular[in];
    tally.min_sigma_squared = half.min_sigma_squared[in];
    return tally;
  }

 private:
  struct Half {
    M nullspace_active{}, failed{}, rank_deficient{}, near_singular{};
    V min_sigma_squared = V{} + INFINITY;
  };
  int64_t updates_ = 0;
  Half halves_[kMaxBatchLanes / kWidth];
};

template <typename Axes>
std::vector<SimulationResult> RunBatchFor(std::span<const ClosedLoopSimulator* const> simulators,
                                          BatchIsa isa, BatchParts parts, const Axes& axes) {
  constexpr int N = Axes::kStages;
  const int width = BatchLanesOf(isa);
  const ClosedLoopSimulator& first = *simulators[0];
  const int64_t total = first.total_samples(), activation = first.activation_sample();
  const int64_t delay = first.delay_samples();

  Batch<Axes> batch;
  for (const ClosedLoopSimulator* simulator : simulators) {
    batch.lanes.push_back(std::make_unique<Lane<Axes>>(*simulator, axes));
  }
  BatchLanes lanes;
  lanes.width = width;
  lanes.stages = N;
  const FusedUpdatePlan& first_plan = *first.fast_path_plan();
  for (int e = 0; e < N; ++e) lanes.axis[e] = first_plan.axis[e];
  lanes.delay_samples = delay;
  lanes.activation_sample = activation;
  lanes.fused_multiply_add = kMulAddIsFused;
  lanes.well_conditioned = FusedGradientProjection<Axes>::kWellConditioned;
  lanes.max_incremental_steps = WaveplateChain::kMaxIncrementalSteps;
  lanes.context = &batch;
  lanes.near_singular = &NearSingular<Axes>;
  lanes.exact_pose = &ExactPose<Axes>;
  lanes.measure_output = &MeasureOutput<Axes>;
  lanes.measure_input = &MeasureInput<Axes>;
  lanes.sin_cos = &LibrarySinCos;
  lanes.vector_input = VectorInput(batch);
  if (lanes.vector_input) {
    const PaperScrambler& scrambler = *batch.lanes[0]->run.input.only_scrambler();
    lanes.input_rotation_axis = scrambler.rotation_elemental();
    lanes.input_kick_axis = scrambler.kick_elemental();
  }
  std::vector<double> line(static_cast<size_t>(delay) * 3 * 4 * kMaxBatchLanes, 0.0);
  lanes.line = line.data();
  for (int l = 0; l < width; ++l) {
    const Lane<Axes>& lane = *batch.lanes[batch.Real(l) ? static_cast<size_t>(l) : 0];
    const FusedUpdatePlan& plan = *lane.simulator.fast_path_plan();
    for (int e = 0; e < N; ++e) lanes.rad_per_unit[e][l] = plan.rad_per_unit[e];
    lanes.step[l] = plan.step;
    lanes.nullspace_step[l] = plan.nullspace_step;
    lanes.has_threshold[l] = plan.threshold.has_value();
    lanes.threshold[l] = plan.threshold.value_or(0.0);
    lanes.measured_loop[l] = plan.loop == LoopMode::kMeasured;
    for (int c = 0; c < 3; ++c) lanes.target[c][l] = plan.target_point[c];
    lanes.noisy_output[l] = batch.Real(l) && lane.run.output_polarimeter.sigma_rad() > 0.0;
    lanes.noisy_input[l] = batch.Real(l) && lane.run.input_polarimeter.sigma_rad() > 0.0;
    if (lanes.vector_input) {
      const PaperScrambler& scrambler = *lane.run.input.only_scrambler();
      for (int c = 0; c < 3; ++c) lanes.sop[c][l] = lane.run.input.current_sop()[c];
      lanes.input_step_cos[l] = scrambler.step_cos();
      lanes.input_step_sin[l] = scrambler.step_sin();
      lanes.input_kick_sigma[l] = scrambler.kick_sigma_rad();
    }
    ElementalPose<N> pose;
    for (int e = 0; e < N; ++e) pose.phi[e] = lane.simulator.initial_phi()[e];
    lane.update.ExactPose(&pose);
    for (int e = 0; e < 4; ++e) {
      lanes.phi[e][l] = pose.phi[e];
      lanes.cos[e][l] = pose.cos[e];
      lanes.sin[e][l] = pose.sin[e];
      for (int64_t slot = 0; slot < delay; ++slot) {
        double* s = line.data() + slot * 3 * 4 * kMaxBatchLanes;
        s[e * kMaxBatchLanes + l] = pose.phi[e];
        s[(4 + e) * kMaxBatchLanes + l] = pose.cos[e];
        s[(8 + e) * kMaxBatchLanes + l] = pose.sin[e];
      }
    }
    lanes.incremental_steps[l] = 0;
  }
#if defined(__x86_64__)
  void (*kernel)(BatchLanes&, const BatchBlock&) =
      isa == BatchIsa::kAvx512 ? &RunBatchBlockAvx512 : &RunBatchBlockAvx2;
#else
  void (*kernel)(BatchLanes&, const BatchBlock&) = nullptr;
  throw std::invalid_argument("RunBatch: no vector kernel for this processor");
#endif

  auto buffers = std::make_unique<BlockBuffers>();
  BatchBlock block;
  for (int c = 0; c < 3; ++c) {
    block.s_in[c] = buffers->s_in[c];
    block.measured_in[c] = buffers->measured_in[c];
    block.s_out[c] = buffers->s_out[c];
  }
  for (int e = 0; e < 4; ++e) {
    block.phi_applied[e] = buffers->phi_applied[e];
    block.gram[e] = buffers->gram[e];
  }
  block.flags = buffers->flags;
  block.normals = buffers->normals;

  const int real = static_cast<int>(batch.lanes.size());
  const bool kernel_only = parts == BatchParts::kKernelOnly;
  LaneUpdateTallies tallies;
  for (int64_t k = 0; k < total;) {
    const int count = static_cast<int>(std::min<int64_t>(kBatchBlock, total - k));
    if (lanes.vector_input && (k == 0 || !kernel_only)) {
      // The kicks' normal draws, lane by lane from each lane's stream (none at sample 0).
      for (int l = 0; l < width; ++l) {
        if (!batch.Real(l)) {
          for (int i = 0; i < count; ++i) {
            buffers->normals[static_cast<size_t>(i) * kMaxBatchLanes + static_cast<size_t>(l)] =
                buffers->normals[static_cast<size_t>(i) * kMaxBatchLanes];
          }
          continue;
        }
        if (!(lanes.input_kick_sigma[l] > 0.0)) continue;
        RandomSource& random = batch.lanes[static_cast<size_t>(l)]->run.input.random_source();
        double draws[kBatchBlock];
        draws[0] = 0.0;
        const int first = k == 0 ? 1 : 0;
        if (count > first) random.NormalBlock(draws + first, count - first);
        for (int i = 0; i < count; ++i) {
          buffers->normals[static_cast<size_t>(i) * kMaxBatchLanes + static_cast<size_t>(l)] =
              draws[i];
        }
      }
    }
    // Otherwise the input and its polarimeter (they do not depend on the control), the lanes
    // interleaved so that their dependency chains (each input follows from the last) overlap.
    for (int i = 0; i < (lanes.vector_input ? 0 : count); ++i) {
      for (int l = 0; l < real; ++l) {
        SimulationRun& run = batch.lanes[static_cast<size_t>(l)]->run;
        const StokesVector& s_in = run.input.Next();
        const size_t at = static_cast<size_t>(i) * kMaxBatchLanes + static_cast<size_t>(l);
        for (int c = 0; c < 3; ++c) buffers->s_in[c][at] = s_in[c];
        if (k + i >= activation) {
          const StokesVector measured = run.input_polarimeter.Measure(s_in);
          for (int c = 0; c < 3; ++c) buffers->measured_in[c][at] = measured[c];
        } else {
          for (int c = 0; c < 3; ++c) buffers->measured_in[c][at] = s_in[c];
        }
      }
    }
    for (int l = real; l < (lanes.vector_input ? 0 : width); ++l) {  // padding: lane 0's input
      for (int i = 0; i < count; ++i) {
        const size_t at = static_cast<size_t>(i) * kMaxBatchLanes;
        for (int c = 0; c < 3; ++c) {
          buffers->s_in[c][at + static_cast<size_t>(l)] = buffers->s_in[c][at];
          buffers->measured_in[c][at + static_cast<size_t>(l)] = buffers->measured_in[c][at];
        }
      }
    }
    block.first_sample = k;
    block.count = count;
    kernel(lanes, block);
    if (kernel_only) {
      k += count;
      continue;
    }
    // The statistics of the true output (each lane's block at once) and of the updates.
    const int first = std::max<int>(0, static_cast<int>(std::min<int64_t>(count, activation - k)));
    for (int l = 0; l < real; ++l) {
      Lane<Axes>& lane = *batch.lanes[static_cast<size_t>(l)];
      const size_t at = static_cast<size_t>(first) * kMaxBatchLanes + static_cast<size_t>(l);
      const double* s_out[3] = {buffers->s_out[0] + at, buffers->s_out[1] + at,
                                buffers->s_out[2] + at};
      lane.run.statistics.AddSamples(k + first, lane.sample_period_s, count - first, s_out,
                                     kMaxBatchLanes);
    }
    // Their controls, every lane at once.
    {
      RunStatistics* statistics[kMaxBatchLanes] = {};
      for (int l = 0; l < real; ++l) statistics[l] = &batch.lanes[static_cast<size_t>(l)]->run.statistics;
      const size_t at = static_cast<size_t>(first) * kMaxBatchLanes;
      const double* phi[4] = {buffers->phi_applied[0] + at, buffers->phi_applied[1] + at,
                              buffers->phi_applied[2] + at, buffers->phi_applied[3] + at};
      RunStatistics::AddControls(statistics, real, phi, count - first, kMaxBatchLanes);
    }
    tallies.Add(*buffers, first, count, [&](int l) -> Lane<Axes>& {
      return *batch.lanes[static_cast<size_t>(l)];
    }, real);
    k += count;
  }

  std::vector<SimulationResult> results;
  for (int l = 0; l < real; ++l) {
    batch.lanes[static_cast<size_t>(l)]->run.statistics.AddUpdates(tallies.Lane(l));
    ControlVector final_phi(N);
    for (int e = 0; e < N; ++e) final_phi[e] = lanes.phi[e][l];
    results.push_back(batch.lanes[static_cast<size_t>(l)]->run.Finish(total, 0, final_phi));
  }
  return results;
}

}  // namespace

std::vector<SimulationResult> RunBatch(std::span<const ClosedLoopSimulator* const> simulators,
                                       BatchIsa isa, BatchParts parts) {
  if (isa == BatchIsa::kNone || simulators.empty() ||
      simulators.size() > static_cast<size_t>(BatchLanesOf(isa))) {
    throw std::invalid_argument("RunBatch: 1 to " + std::to_string(BatchLanesOf(isa)) +
                                " simulators on a vector instruction set");
  }
  for (const ClosedLoopSimulator* simulator : simulators) {
    if (!CanShareBatch(*simulators[0], *simulator)) {
      throw std::invalid_argument(
          "RunBatch: the runs do not share a batch (the fast path, stage axes, delay, sample "
          "count and activation must be the same)");
    }
  }
  const FusedUpdatePlan& plan = *simulators[0]->fast_path_plan();
  return DispatchStageAxes(plan.axis, plan.stages, [&](const auto& axes) {
    return RunBatchFor(simulators, isa, parts, axes);
  });
}

}  // namespace dpc
