#pragma once
// The input SOP of a simulation: an initial SOP driven by a list of disturbances.
//
// Timing (dt = 1/fs, t_k = k·dt the time of sample k):
//
//   S_in[0] = initial_sop / |initial_sop|
//   S_in[k] = N( D_m,t ∘ … ∘ D_1,t (S_in[k−1]) ),   t = t_{k−1} = (k − 1)·dt,   k ≥ 1
//
// i.e. disturbance D_1 first, each evaluated once at the start t_{k−1} of the interval
// [t_{k−1}, t_k) that leads from sample k − 1 to sample k; N(S) = S·(3 − |S|²)/2
// (RenormalizeNearUnit) keeps |S| = 1 to round-off over any number of samples. Call k of Next()
// (0-based) returns S_in[k]; the first call returns the initial SOP and applies nothing.
//
// Randomness: one RandomSource(seed, stream 1) shared by the disturbances in order, so a run is
// reproducible from the seed, and adding polarimeter noise (stream 2) does not change the input.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "dpc/config/scenario_config.h"
#include "dpc/disturbance/disturbance.h"
#include "dpc/disturbance/paper_scrambler.h"
#include "dpc/disturbance/random_source.h"

namespace dpc {

class InputSopGenerator {
 public:
  /// The RandomSource stream the input uses.
  static constexpr uint64_t kRandomStream = 1;

  /// `initial_sop` a finite unit Stokes vector (within kUnitNormTolerance; it is normalized);
  /// `disturbances` non-null, applied in order (may be empty: the SOP holds still);
  /// `sample_rate_hz` finite and > 0. Throws std::invalid_argument otherwise.
  InputSopGenerator(const StokesVector& initial_sop,
                    std::vector<std::unique_ptr<Disturbance>> disturbances, uint64_t seed,
                    double sample_rate_hz);

  InputSopGenerator(InputSopGenerator&&) = default;
  InputSopGenerator& operator=(InputSopGenerator&&) = default;

  /// Real-time. S_in[k] for call k (0-based); see the file comment. The reference stays valid
  /// until the next call.
  const StokesVector& Next() {
    if (next_index_ > 0) {
      const double t_s = static_cast<double>(next_index_ - 1) * sample_period_s_;
      if (only_scrambler_ != nullptr) {
        // The paper's input, called directly (inlined) rather than through the vtable.
        only_scrambler_->PaperScrambler::Advance(t_s, &sop_, random_);
      } else {
        for (const std::unique_ptr<Disturbance>& disturbance : disturbances_) {
          disturbance->Advance(t_s, &sop_, random_);
        }
      }
      RenormalizeNearUnit(&sop_);
    }
    ++next_index_;
    return sop_;
  }

  /// The most samples one block (BeginBlock) holds.
  static constexpr int kMaxBlock = 64;

  /// Where a block's SOP chain stands: kept by the caller (a local, so in registers) while it
  /// steps through the block. See BeginBlock.
  struct BlockCursor {
    double x, y, z;
  };

  /// Real-time. The input a block at a time, for a loop that interleaves it with other work (the
  /// simulator's fast path):
  ///
  ///   BlockCursor cursor = input.BeginBlock(count);         // 0 ≤ count ≤ kMaxBlock
  ///   for (int i = 0; i < count; ++i) s_in = input.Step(i, &cursor);  // in this order
  ///   input.EndBlock(cursor);
  ///
  /// gives, bit for bit, what `count` calls of Next() would. For the paper's scrambler alone on
  /// elemental axes, BeginBlock draws the block's normals and computes its kicks' sines (none of
  /// which depends on the SOP, so they overlap in the pipeline), and each Step is only the
  /// rotations and the renormalization: the short chain from one SOP to the next, which the
  /// caller's other work hides. Any other input is advanced by Next() in BeginBlock and read back
  /// by Step. Throws std::invalid_argument for a count out of range (not real-time then).
  BlockCursor BeginBlock(int count);

  /// Real-time. S_in of the block's sample i; see BeginBlock.
  [[gnu::always_inline]] StokesVector Step(int i, BlockCursor* cursor) const {
    if (!block_chained_) return block_sops_[i];
    double x = cursor->x, y = cursor->y, z = cursor->z;
    if (i < block_first_) return StokesVector(x, y, z);  // the initial SOP: nothing applied
    // PaperScrambler::Advance and RenormalizeNearUnit (with Eigen's squaredNorm order).
    if (block_paper_axes_) {  // the axes fixed: RotateElemental's switch folds away
      RotateElemental(ElementalAxis::kS3, block_step_cos_, block_step_sin_, x, y, z);
      RotateElemental(ElementalAxis::kS2, block_cos_kick_[i], block_sin_kick_[i], x, y, z);
    } else {
      RotateElemental(block_step_axis_, block_step_cos_, block_step_sin_, x, y, z);
      RotateElemental(block_kick_axis_, block_cos_kick_[i], block_sin_kick_[i], x, y, z);
    }
    const double factor = 0.5 * (3.0 - ((x * x + y * y) + z * z));
    *cursor = BlockCursor{x * factor, y * factor, z * factor};
    return StokesVector(cursor->x, cursor->y, cursor->z);
  }

  /// Real-time. Ends the block: the generator goes on from its last SOP.
  void EndBlock(const BlockCursor& cursor) {
    if (block_chained_) sop_ = StokesVector(cursor.x, cursor.y, cursor.z);
  }

  /// The index k of the sample the last Next() returned; −1 before the first call.
  int64_t sample_index() const { return next_index_ - 1; }
  /// The SOP the last Next() returned (the initial SOP before the first call).
  const StokesVector& current_sop() const { return sop_; }
  const StokesVector& initial_sop() const { return initial_sop_; }
  double sample_period_s() const { return sample_period_s_; }
  const std::vector<std::unique_ptr<Disturbance>>& disturbances() const { return disturbances_; }

  /// For the batched simulator, which runs the paper scrambler itself in vector lanes: the
  /// scrambler when it is the only disturbance (else nullptr), and the stream it draws from.
  const PaperScrambler* only_scrambler() const { return only_scrambler_; }
  RandomSource& random_source() { return random_; }

  /// "initial [1, 0, 0]; paper scrambler: …; random walk: …".
  std::string Describe() const;

 private:
  StokesVector initial_sop_;
  std::vector<std::unique_ptr<Disturbance>> disturbances_;
  RandomSource random_;
  double sample_period_s_;
  StokesVector sop_;
  int64_t next_index_ = 0;
  PaperScrambler* only_scrambler_ = nullptr;  ///< set when it is the only disturbance

  // The block of BeginBlock / Step.
  bool block_chained_ = false;  ///< Step runs the scrambler (else it reads block_sops_)
  int block_first_ = 0;         ///< 1 when the block starts with the initial SOP
  bool block_paper_axes_ = false;  ///< the paper's: about S3, kicks about S2
  ElementalAxis block_step_axis_ = ElementalAxis::kGeneral;
  ElementalAxis block_kick_axis_ = ElementalAxis::kGeneral;  ///< kGeneral: no kicks
  double block_step_cos_ = 1.0, block_step_sin_ = 0.0;
  double block_cos_kick_[kMaxBlock] = {}, block_sin_kick_[kMaxBlock] = {};
  StokesVector block_sops_[kMaxBlock];
};

/// Not real-time. The generator for `input` (MakeDisturbance for each entry, in order; a
/// recorded input: its first SOP, then a RecordedInputDisturbance). Throws
/// std::invalid_argument for a bad initial SOP or disturbance.
InputSopGenerator MakeInputSopGenerator(const InputConfig& input, uint64_t seed,
                                        double sample_rate_hz);

}  // namespace dpc
