#pragma once
// The one exception a scenario problem raises: where (a field path in scenario.proto, or a
// "file.pbtxt:line:column" for a syntax error) and what (the value, and what was expected).
//
//   ScenarioError("controller.step",
//                 "-0.1 is not > 0; the task step must be positive (typical 0.01 to 1)")
//   what() == "controller.step: -0.1 is not > 0; the task step must be positive (typical …)"
//
// Field paths use the names a user writes in the text file: message fields joined by '.',
// repeated elements with their 0-based index, oneof members by their own name, e.g.
// "stages[1].map.table.angle_rad[3]" or "input.disturbances[0].paper_scrambler.rate_rad_per_s".
//
// It derives from std::invalid_argument, so callers that only care that the configuration is
// bad can catch that.

#include <memory>
#include <stdexcept>
#include <string>

namespace dpc {

class ScenarioError : public std::invalid_argument {
 public:
  /// `location`: a field path or "file:line:column"; `message`: what is wrong. what() is
  /// `location + ": " + message` (just `message` when the location is empty).
  ScenarioError(std::string location, std::string message);

  /// The field path or file position, e.g. "stages[1].map.table.angle_rad[3]".
  const std::string& location() const noexcept { return parts_->location; }
  /// What is wrong, without the location.
  const std::string& message() const noexcept { return parts_->message; }

 private:
  struct Parts {
    std::string location;
    std::string message;
  };
  // Shared and immutable so that copying the exception cannot throw (like std::runtime_error).
  std::shared_ptr<const Parts> parts_;
};

}  // namespace dpc
