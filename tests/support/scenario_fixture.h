#pragma once
// Shared set-up for the scenario validation tests (tests/unit/config/*_validation_test.cc): the
// paper's valid scenario, which each test breaks in one field, and the error ValidateScenario
// then reports (its location is the field path the test checks).

#include <gtest/gtest.h>

#include <limits>
#include <optional>
#include <string>

#include "dpc/config/scenario_config.h"
#include "dpc/config/scenario_error.h"
#include "dpc/config/scenario_validation.h"

namespace dpc::testing {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();

// Starts from the paper's valid scenario; each test breaks one field and checks the path.
class ScenarioFixture : public ::testing::Test {
 protected:
  /// The error ValidateScenario reports, or nullopt if it accepts the scenario.
  std::optional<ScenarioError> Error() const {
    try {
      ValidateScenario(scenario_);
    } catch (const ScenarioError& e) {
      return e;
    }
    return std::nullopt;
  }
  /// The location of the error, or "(valid)".
  std::string ErrorLocation() const {
    const auto error = Error();
    return error ? error->location() : "(valid)";
  }
  std::string ErrorMessage() const {
    const auto error = Error();
    return error ? error->message() : "(valid)";
  }

  ScenarioConfig scenario_ = PaperScenario("131");
};

}  // namespace dpc::testing
