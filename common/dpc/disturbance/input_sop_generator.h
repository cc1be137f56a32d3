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
};

/// Not real-time. The generator for `input` (MakeDisturbance for each entry, in order; a
/// recorded input: its first SOP, then a RecordedInputDisturbance). Throws
/// std::invalid_argument for a bad initial SOP or disturbance.
InputSopGenerator MakeInputSopGenerator(const InputConfig& input, uint64_t seed,
                                        double sample_rate_hz);

}  // namespace dpc
