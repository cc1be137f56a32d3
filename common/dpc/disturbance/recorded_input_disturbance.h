#pragma once
// The input SOP of a recorded session: S_in[k] is the recording's k-th sample, whatever came
// before (the "disturbance" sets the SOP instead of rotating it). Past the recording's end the
// last SOP is held. InputSopGenerator makes it the only disturbance of an input whose initial
// SOP is the recording's first (MakeInputSopGenerator, for InputConfig::recorded).

#include <cstdint>
#include <memory>
#include <string>

#include "dpc/config/scenario_config.h"
#include "dpc/disturbance/disturbance.h"

namespace dpc {

class RecordedInputDisturbance final : public Disturbance {
 public:
  /// `recorded` non-null with at least one sample (ValidateScenario checks the SOPs). Throws
  /// std::invalid_argument otherwise.
  explicit RecordedInputDisturbance(std::shared_ptr<const RecordedInput> recorded);

  /// Real-time. Call k (0-based) sets *sop to S_in[k + 1] (the call for the interval that leads
  /// to sample k + 1); the last SOP past the end. Draws nothing; ignores t_s.
  void Advance(double t_s, StokesVector* sop, RandomSource& random) override {
    (void)t_s;
    (void)random;
    if (next_ + 1 < size_) ++next_;
    *sop = recorded_->sops[next_];
  }

  std::string Describe() const override;

 private:
  std::shared_ptr<const RecordedInput> recorded_;
  size_t size_;
  size_t next_ = 0;  ///< the index last set
};

}  // namespace dpc
