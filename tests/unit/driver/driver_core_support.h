#pragma once
// What the driver core's tests share: commands, what a state says as plain vectors, a bench
// that publishes the sample a command answers, the fixture.

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dpc/config/scenario_config.h"
#include "driver_core.h"

namespace dpc::services::testing {

constexpr int64_t kUs = 1000;
constexpr int64_t kMs = 1000 * kUs;

inline ControlVector Controls(const std::vector<double>& values) {
  ControlVector out(static_cast<Eigen::Index>(values.size()));
  for (size_t i = 0; i < values.size(); ++i) out[static_cast<Eigen::Index>(i)] = values[i];
  return out;
}

inline ControllerCommand Command(const std::string& id, int priority, std::vector<double> phi, uint64_t sample,
                          int64_t sample_time_ns = 0) {
  ControllerCommand c;
  c.controller_id = id;
  c.priority = priority;
  c.answers_sample = sample;
  c.sample_time_ns = sample_time_ns;
  c.phi = Controls(phi);
  return c;
}

// What a state says, as plain vectors.
inline std::vector<double> Phi(const DriverState& state) {
  return std::vector<double>(state.motion.phi.data(), state.motion.phi.data() + state.motion.phi.size());
}
inline std::vector<double> Rates(const DriverState& state) {
  if (!state.motion.moving) return {};
  return std::vector<double>(state.motion.rate_per_s.data(),
                             state.motion.rate_per_s.data() + state.motion.rate_per_s.size());
}
inline std::vector<bool> Saturated(const DriverState& state) {
  return std::vector<bool>(state.saturated.begin(), state.saturated.begin() + state.control_count());
}
inline int64_t RampEnd(const DriverState& state) { return state.motion.moving ? state.motion.end_ns : state.motion.start_ns; }

/// The bench publishes the sample a command answers (if it is newer than any so far), then the
/// command arrives: what the driver sees on a running bench.
inline std::optional<DriverState> Send(DriverCore& core, const ControllerCommand& command, int64_t now_ns,
                                int64_t wall_ns) {
  if (command.answers_sample > core.newest_sample()) {
    core.OnSample(command.answers_sample, command.sample_time_ns, wall_ns);
  }
  return core.OnCommand(command, now_ns, wall_ns);
}

class DriverCoreTest : public ::testing::Test {
 protected:
  DriverCoreTest() : backend_(ControlVector::Zero(3)), core_(StagesFromAxes("131"), ShortGrace(), &backend_) {}
  /// The arbitration's mechanics at a 1.2-ms grace (the default is longer: stand-ins fill it).
  static DriverSettings ShortGrace() {
    DriverSettings settings;
    settings.min_silence_s = 1.2e-3;
    return settings;
  }
  SimulatedWaveplates backend_;
  DriverCore core_;
};

}  // namespace dpc::services::testing
