#include "dpc/config/scenario_error.h"

#include <utility>

namespace dpc {
namespace {

std::string Join(const std::string& location, const std::string& message) {
  return location.empty() ? message : location + ": " + message;
}

}  // namespace

ScenarioError::ScenarioError(std::string location, std::string message)
    : std::invalid_argument(Join(location, message)),
      parts_(std::make_shared<const Parts>(Parts{std::move(location), std::move(message)})) {}

}  // namespace dpc
