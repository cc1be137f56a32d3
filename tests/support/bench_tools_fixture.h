#pragma once
// A real bench for the tests of dpc's DDS tools (topic, target, monitor, record): dpc-driver,
// dpc-controller and dpc-polarimeter started as processes on a test's private DDS domain with the
// loopback-only profile, stopped (SIGINT, then SIGKILL) and reaped by RAII in reverse order, also
// when the test fails. Needs DPC_DRIVER_BINARY, DPC_CONTROLLER_BINARY, DPC_POLARIMETER_BINARY
// besides CommandLineTest's definitions.

#include <nlohmann/json.hpp>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "support/command_line_fixture.h"
#include "support/process.h"

namespace dpc::testing {

class BenchToolsTest : public CommandLineTest {
 protected:
  void TearDown() override {
    // Stop the bench before its files go, in reverse order (polarimeter first).
    while (!bench_.empty()) bench_.pop_back();
    CommandLineTest::TearDown();
  }

  /// Starts a process (kept until the test ends); its output in files named after `tag`.
  Process& Start(const std::string& tag, const std::vector<std::string>& argv) {
    bench_.push_back(std::make_unique<Process>(argv, dir_ / (tag + ".out"), dir_ / (tag + ".err")));
    return *bench_.back();
  }

  /// The bench on `domain`: driver, controller A, polarimeter at `rate_hz`.
  void StartBench(int domain, int rate_hz = 200) {
    const std::string d = std::to_string(domain);
    Start("driver", {DPC_DRIVER_BINARY, "--domain", d, "--device-record", (dir_ / "driver.record").string()});
    Start("controller", {DPC_CONTROLLER_BINARY, "--domain", d, "--id", "A"});
    // --settle-samples 0: below 1 kHz the default 1000 exceeds the scenario's samples
    // (duration_s × rate) and the polarimeter refuses to start.
    Start("polarimeter", {DPC_POLARIMETER_BINARY, "--domain", d, "--rate-hz", std::to_string(rate_hz),
                          "--settle-samples", "0"});
    for (const auto& p : bench_) ASSERT_TRUE(p->running());
  }

  /// Waits until the bench's controller is obeyed: one state sample naming it.
  void AwaitObeyed(int domain, const std::string& controller) {
    const bool obeyed = Eventually(
        [&] {
          const Result r = Dpc({"topic", "echo", "state", "--json", "--count", "1", "--timeout-s", "5",
                                "--domain", std::to_string(domain)});
          if (r.exit_code != 0) return false;
          const auto j = nlohmann::json::parse(r.out, nullptr, false);
          return !j.is_discarded() && j["mode"] == "DRIVER_ACTIVE" &&
                 j["obeyed_controller_id"] == controller;
        },
        std::chrono::seconds(30));
    ASSERT_TRUE(obeyed) << "the driver never obeyed controller " << controller << "\n"
                        << Slurp(dir_ / "driver.err") << Slurp(dir_ / "controller.err");
  }

  std::vector<std::unique_ptr<Process>> bench_;
};

}  // namespace dpc::testing
