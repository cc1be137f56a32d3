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
