// The service skeleton: stop() wakes run() at once; SIGTERM stops a running service; ServiceMain
// maps configuration and initialization failures to their exit codes.
#include "service.h"

#include <gtest/gtest.h>
#include <spdlog/sinks/stdout_color_sinks.h>

#include <signal.h>
#include <unistd.h>
#include <thread>

namespace dpc::services {
namespace {

using namespace std::chrono_literals;

/// Waits for stop() for up to an hour; records how long it waited.
class WaitingService final : public Service {
 public:
  struct Options {
    std::string fail_with;  ///< "scenario", "configuration", "start", "run" or ""
  };
  static void AddOptions(CLI::App& app, Options* o) { app.add_option("--fail-with", o->fail_with); }
  static std::string LogName(const Options&) { return "test"; }

  WaitingService() = default;
  WaitingService(const CommonOptions&, const Options& o) : fail_with_(o.fail_with) {
    if (fail_with_ == "scenario") throw ScenarioError("controller.step", "-1 is not > 0");
    if (fail_with_ == "configuration") throw ConfigurationError("--rate-hz contradicts the scenario");
    if (fail_with_ == "start") throw std::runtime_error("no participant");
    if (fail_with_ == "signal") kill(getpid(), SIGTERM);  // before run(): it must stop at once
  }

  /// "stuck": a loop the guard watches, which never turns.
  std::optional<double> LongestTurnS() const override {
    return fail_with_ == "stuck" ? std::optional<double>(0.0) : std::nullopt;
  }

  cli::ExitCode run() override {
    if (fail_with_ == "run") throw std::runtime_error("lost the device");
    if (fail_with_ == "stuck") {
      GuardPhase("a call that never returns");
      for (;;) std::this_thread::sleep_for(1s);  // deaf to stop(), as a thread blocked in a deadlock
    }
    const auto start = std::chrono::steady_clock::now();
    woken_ = WaitForStopFor(1h);
    waited_ = std::chrono::steady_clock::now() - start;
    return cli::ExitCode::kOk;
  }

  bool woken_ = false;
  std::chrono::steady_clock::duration waited_{};
  int stops_ = 0;

 private:
  void OnStop() override { ++stops_; }
  std::string fail_with_;
};

TEST(ServiceTest, StopWakesRunAtOnceAndOnlyOnce) {
  WaitingService service;
  std::thread runner([&] { service.run(); });
  std::this_thread::sleep_for(20ms);  // let it wait (a longer wait only makes the test slower)
  service.stop();
  service.stop();
  runner.join();
  EXPECT_TRUE(service.woken_);
  EXPECT_TRUE(service.stopped());
  EXPECT_EQ(service.stops_, 1);
  EXPECT_LT(service.waited_, 10s) << "woken by stop(), not by the hour's timeout";
}

TEST(ServiceTest, AStopBeforeRunIsNotLost) {
  WaitingService service;
  service.stop();
  EXPECT_EQ(service.run(), cli::ExitCode::kOk);
  EXPECT_TRUE(service.woken_);
}

int Main(std::vector<std::string> args) {
  args.insert(args.begin(), "test-service");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return ServiceMain<WaitingService>(static_cast<int>(argv.size()), argv.data(), "a test service");
}

TEST(ServiceMainTest, MapsEachKindOfFailureToItsExitCode) {
  EXPECT_EQ(Main({"--no-such-option"}), cli::ToInt(cli::ExitCode::kInvalidInput));
  EXPECT_EQ(Main({"--fail-with", "scenario"}), cli::ToInt(cli::ExitCode::kInvalidInput));
  EXPECT_EQ(Main({"--fail-with", "configuration"}), cli::ToInt(cli::ExitCode::kInvalidInput));
  EXPECT_EQ(Main({"--fail-with", "start"}), cli::ToInt(cli::ExitCode::kInitializationError));
  EXPECT_EQ(Main({"--fail-with", "run"}), cli::ToInt(cli::ExitCode::kRuntimeError));
  EXPECT_EQ(Main({"--help"}), cli::ToInt(cli::ExitCode::kOk));
}

TEST(ServiceMainTest, AServiceWhoseLoopDoesNotTurnSaysWhereAndExitsWithCode1) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(Main({"--fail-with", "stuck", "--stuck-exit-s", "1"}), ::testing::ExitedWithCode(1),
              "stuck: its loop has not turned for [0-9.]+ s \\(stuck in: a call that never returns\\)");
}

TEST(ServiceMainTest, ExitStuckLogsWhyAndExitsWithCode1) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        spdlog::set_default_logger(spdlog::stderr_color_mt("guard"));  // as a service logs (SetUpLogging)
        ExitStuck("stuck: its loop has not turned for 10.0 s");
      },
      ::testing::ExitedWithCode(1), "critical.*stuck: its loop has not turned for 10.0 s");
}

TEST(ServiceMainTest, TheStuckLimitIsCheckedAndAServiceWithoutALoopIsNotJudged) {
  EXPECT_EQ(Main({"--stuck-exit-s", "0.5"}), cli::ToInt(cli::ExitCode::kInvalidInput));
  EXPECT_EQ(Main({"--stuck-exit-s", "nan"}), cli::ToInt(cli::ExitCode::kInvalidInput));
  EXPECT_EQ(Main({"--stuck-exit-s", "-1"}), cli::ToInt(cli::ExitCode::kInvalidInput));
  // The limit is raised to a loop's own longest turn plus a margin, and 0 turns it off.
  EXPECT_EQ(GuardedTurnLimitS(10.0, 0.0), 10.0);
  EXPECT_EQ(GuardedTurnLimitS(10.0, 50.1), 52.1);
  EXPECT_EQ(GuardedTurnLimitS(0.0, 0.0), 0.0);
  EXPECT_EQ(GuardedTurnLimitS(10.0, std::nullopt), 0.0);
}

TEST(ServiceMainTest, SigtermStopsTheServiceCleanly) {
  // The signal arrives while the service is being built: blocked until the watcher takes it,
  // then the service stops at once and exits 0.
  EXPECT_EQ(Main({"--fail-with", "signal"}), cli::ToInt(cli::ExitCode::kOk));
}

}  // namespace
}  // namespace dpc::services
