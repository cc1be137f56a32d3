#include "dpc/disturbance/input_sop_generator.h"

#include <fmt/format.h>

#include <stdexcept>
#include <utility>

#include "dpc/disturbance/disturbance_factory.h"
#include "dpc/disturbance/recorded_input_disturbance.h"

namespace dpc {

InputSopGenerator::InputSopGenerator(const StokesVector& initial_sop,
                                     std::vector<std::unique_ptr<Disturbance>> disturbances,
                                     uint64_t seed, double sample_rate_hz)
    : disturbances_(std::move(disturbances)),
      random_(seed, kRandomStream),
      sample_period_s_(SamplePeriodFromRate(sample_rate_hz, "input SOP generator")) {
  RequireUnitStokes(initial_sop, "input SOP generator: initial SOP");
  initial_sop_ = initial_sop.normalized();
  sop_ = initial_sop_;
  for (size_t i = 0; i < disturbances_.size(); ++i) {
    if (disturbances_[i] == nullptr) {
      throw std::invalid_argument(
          fmt::format("input SOP generator: disturbance {} is null", i));
    }
  }
  if (disturbances_.size() == 1) {
    only_scrambler_ = dynamic_cast<PaperScrambler*>(disturbances_[0].get());
  }
}

InputSopGenerator::BlockCursor InputSopGenerator::BeginBlock(int count) {
  if (count < 0 || count > kMaxBlock) {
    throw std::invalid_argument(fmt::format(
        "input SOP generator: a block of {} samples (0 to {} allowed)", count, kMaxBlock));
  }
  const PaperScrambler* scrambler = only_scrambler_;
  const double sigma_rad = scrambler != nullptr ? scrambler->kick_sigma_rad() : 0.0;
  const bool kicks = sigma_rad > 0.0;
  block_chained_ = scrambler != nullptr &&
                   scrambler->rotation_elemental() != ElementalAxis::kGeneral &&
                   (!kicks || scrambler->kick_elemental() != ElementalAxis::kGeneral);
  if (!block_chained_) {
    for (int i = 0; i < count; ++i) block_sops_[i] = Next();
    return BlockCursor{sop_[0], sop_[1], sop_[2]};
  }
  block_first_ = next_index_ == 0 ? 1 : 0;  // Next's first call returns the initial SOP
  block_step_axis_ = scrambler->rotation_elemental();
  block_kick_axis_ = kicks ? scrambler->kick_elemental() : ElementalAxis::kGeneral;
  block_paper_axes_ = block_step_axis_ == ElementalAxis::kS3 && block_kick_axis_ == ElementalAxis::kS2;
  block_step_cos_ = scrambler->step_cos();
  block_step_sin_ = scrambler->step_sin();
  next_index_ += count;
  const BlockCursor cursor{sop_[0], sop_[1], sop_[2]};
  if (!kicks) return cursor;
  // PaperScrambler::Advance's kick: SinCos(σ·normal), one draw per advanced sample.
  double angle_rad[kMaxBlock];
  if (count > block_first_) random_.NormalBlock(angle_rad + block_first_, count - block_first_);
  for (int i = block_first_; i < count; ++i) angle_rad[i] *= sigma_rad;
  int beyond = 0;  // an integer OR: a reduction the compiler vectorizes
  for (int i = block_first_; i < count; ++i) {
    beyond |= !(angle_rad[i] > -kSmallAngleLimit && angle_rad[i] < kSmallAngleLimit);
  }
  for (int i = block_first_; i < count; ++i) {
    if (beyond == 0) {
      SmallAngleSinCos(angle_rad[i], &block_sin_kick_[i], &block_cos_kick_[i]);
    } else {
      SinCos(angle_rad[i], &block_sin_kick_[i], &block_cos_kick_[i]);
    }
  }
  return cursor;
}

std::string InputSopGenerator::Describe() const {
  std::string text = "initial " + FormatStokes(initial_sop_);
  for (const std::unique_ptr<Disturbance>& disturbance : disturbances_) {
    text += "; " + disturbance->Describe();
  }
  return text;
}

InputSopGenerator MakeInputSopGenerator(const InputConfig& input, uint64_t seed,
                                        double sample_rate_hz) {
  std::vector<std::unique_ptr<Disturbance>> disturbances;
  if (input.recorded != nullptr) {
    if (!input.disturbances.empty()) {
      throw std::invalid_argument("input: disturbances beside a recorded input");
    }
    if (input.recorded->sops.empty()) throw std::invalid_argument("input.recorded: no sample");
    disturbances.push_back(std::make_unique<RecordedInputDisturbance>(input.recorded));
    return InputSopGenerator(input.recorded->sops.front(), std::move(disturbances), seed, sample_rate_hz);
  }
  disturbances.reserve(input.disturbances.size());
  for (size_t i = 0; i < input.disturbances.size(); ++i) {
    try {
      disturbances.push_back(MakeDisturbance(input.disturbances[i], sample_rate_hz));
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument(fmt::format("input.disturbances[{}]: {}", i, error.what()));
    }
  }
  return InputSopGenerator(input.initial_sop, std::move(disturbances), seed, sample_rate_hz);
}

}  // namespace dpc
