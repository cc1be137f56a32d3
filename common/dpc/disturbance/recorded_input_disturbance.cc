#include "dpc/disturbance/recorded_input_disturbance.h"

#include <fmt/format.h>

#include <stdexcept>
#include <utility>

namespace dpc {

RecordedInputDisturbance::RecordedInputDisturbance(std::shared_ptr<const RecordedInput> recorded)
    : recorded_(std::move(recorded)), size_(recorded_ == nullptr ? 0 : recorded_->sops.size()) {
  if (size_ == 0) throw std::invalid_argument("recorded input: no sample");
}

std::string RecordedInputDisturbance::Describe() const {
  return fmt::format("recorded input: {} samples of {}", size_, recorded_->source);
}

}  // namespace dpc
