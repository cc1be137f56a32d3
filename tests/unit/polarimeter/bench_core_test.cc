// BenchCore: the simulated optical bench behind the polarimeter service, through a fake link.
#include "bench_core.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_error.h"
#include "dpc/control/control_law_factory.h"
#include "dpc/control/polarization_controller.h"
#include "dpc/sim/closed_loop_simulator.h"
#include "support/line_server.h"

namespace dpc::services {
namespace {

constexpr double kTolerance = 1e-12;

/// Records what the bench publishes; the other calls do nothing unless a test overrides them.
class RecordingLink : public BenchLink {
 public:
  void Publish(const BenchSample& sample) override { published.push_back(sample); }
  std::optional<ControlVector> AwaitAnswer(const BenchSample&, std::string* why) override {
    *why = "no answer";
    return std::nullopt;
  }
  bool TakeApplied(WaveplateMotion*) override { return false; }
  std::optional<TargetConfig> TargetChange() override { return std::nullopt; }
  bool stop_requested() override { return false; }

  std::vector<BenchSample> published;
};

/// Answers every sample with the command a PolarizationController computes from it, on the
/// sample clock, as ClosedLoopSimulator::RunGeneral does: the pose it passes to Update is the
/// previous one advanced by ComputePoseFrom, as the simulator's delay line holds it, so the
/// controller's arithmetic is the simulator's.
class ControllerLink : public RecordingLink {
 public:
  explicit ControllerLink(const BenchCore& bench)
      : chain_(bench.chain()),
        controller_(bench.chain(), bench.target(), bench.scenario().controller,
                    BuildLawTiming(bench.scenario().simulation),
                    BuildInitialPhi(bench.scenario().controller, bench.control_count())) {
    chain_.ComputePose(controller_.phi(), &pose_);
  }
  std::optional<ControlVector> AwaitAnswer(const BenchSample& sample, std::string*) override {
    input_.s_in = sample.s_in;
    input_.s_out = sample.s_out;
    controller_.Update(input_, pose_);
    chain_.ComputePoseFrom(pose_, controller_.phi(), &pose_);
    return controller_.phi();
  }

 private:
  const WaveplateChain& chain_;
  PolarizationController controller_;
  ControlInput input_;
  ChainPose pose_;
};

/// Answers `answers` samples with `phi`, then ends the run as a link that timed out does.
class StoppingLink : public RecordingLink {
 public:
  StoppingLink(int answers, ControlVector phi) : answers_(answers), phi_(std::move(phi)) {}
  std::optional<ControlVector> AwaitAnswer(const BenchSample&, std::string* why) override {
    if (answers_-- > 0) return phi_;
    *why = "timeout: no state for 2 s";
    return std::nullopt;
  }

 private:
  int answers_;
  ControlVector phi_;
};

// A short run of the paper's scenario at 50 MHz: 100 000 samples before activation, 10 000 after.
ScenarioConfig ShortPaperScenario() {
  ScenarioConfig scenario = PaperScenario("131");
  scenario.simulation.duration_s = 2.2e-3;
  scenario.controller.activation_s = 2e-3;
  return scenario;
}

BenchSettings Lockstep() {
  BenchSettings settings;
  settings.lockstep = true;
  return settings;
}

TEST(BenchCoreLockstep, AnsweredByTheSimulatorsControllerReproducesTheGeneralLoop) {
  const ScenarioConfig scenario = ShortPaperScenario();
  // A user law factory keeps the simulator on the general loop (PolarizationController).
  ClosedLoopSimulator simulator(scenario, [](const ControllerConfig& c, const LawTiming& timing,
                                             int n, bool point) {
    return MakeControlLaw(c, timing, n, point);
  });
  ASSERT_FALSE(simulator.uses_fast_path());
  const SimulationResult simulated = simulator.Run();
  const RunSummary& expected = simulated.summary;

  BenchCore bench(scenario, Lockstep());
  ControllerLink link(bench);
  const BenchReport report = bench.Run(&link, nullptr);
  const RunSummary& actual = report.result.summary;

  EXPECT_EQ(report.stop_reason, "end of scenario");
  EXPECT_EQ(report.samples, 110'000);
  EXPECT_EQ(report.published, 10'000);
  EXPECT_EQ(actual.samples, expected.samples);
  ASSERT_GT(expected.statistics_samples, 0);  // the loop locked: the error figures are real
  EXPECT_EQ(actual.statistics_samples, expected.statistics_samples);
  // Not bit for bit: the simulator's plant applies the pose the controller issued, derived by
  // angle addition (ComputePoseFrom), while the bench computes the applied pose exactly
  // (ComputePose); their sines and cosines differ by ~2e-15 (measured), which moves the error
  // figures by < 1e-13 degree over this run. Everything else is the same arithmetic.
  constexpr double kRoundOffDeg = 1e-12;
  EXPECT_NEAR(actual.error_deg.mean, expected.error_deg.mean, kRoundOffDeg);
  EXPECT_NEAR(actual.error_deg.max, expected.error_deg.max, kRoundOffDeg);
  EXPECT_NEAR(actual.error_deg.p99, expected.error_deg.p99, kRoundOffDeg);
  ASSERT_EQ(report.result.final_phi.size(), simulator.chain().control_count());
  EXPECT_LT((report.result.final_phi - simulated.final_phi).norm(), kTolerance);
}

TEST(BenchCoreLockstep, PublishesFromTheActivationSampleNumberedFromOneAtSampleZero) {
  BenchCore bench(ShortPaperScenario(), Lockstep());
  StoppingLink link(3, BuildInitialPhi(bench.scenario().controller, bench.control_count()));
  bench.Run(&link, nullptr);
  ASSERT_EQ(link.published.size(), 4u);  // three answered, the fourth waited for in vain
  // Activation at 2 ms is sample 100 000 at 50 MHz; its sequence number counts from sample 0.
  for (size_t i = 0; i < link.published.size(); ++i) {
    const BenchSample& sample = link.published[i];
    EXPECT_EQ(sample.sequence, 100'001u + i);
    EXPECT_EQ(sample.time_ns, 2'000'000 + 20 * static_cast<int64_t>(i));
    EXPECT_TRUE(sample.lockstep);
  }
}

TEST(BenchCoreLockstep, AnActivationAtZeroPublishesSampleOneFirst) {
  ScenarioConfig scenario = ShortPaperScenario();
  scenario.controller.activation_s = 0.0;
  BenchCore bench(scenario, Lockstep());
  StoppingLink link(0, ControlVector());
  bench.Run(&link, nullptr);
  ASSERT_EQ(link.published.size(), 1u);
  EXPECT_EQ(link.published[0].sequence, 1u);
  EXPECT_EQ(link.published[0].time_ns, 0);
}

TEST(BenchCoreLockstep, AMissingAnswerEndsTheRunWithTheLinksReason) {
  BenchCore bench(ShortPaperScenario(), Lockstep());
  StoppingLink link(5, BuildInitialPhi(bench.scenario().controller, bench.control_count()));
  const BenchReport report = bench.Run(&link, nullptr);
  EXPECT_EQ(report.stop_reason, "timeout: no state for 2 s");
  EXPECT_EQ(report.published, 6);
  EXPECT_EQ(report.samples, 100'005);  // the unanswered sample does not count as run
  EXPECT_EQ(report.result.summary.samples, 100'005);
}

// Real time: the bench's own clock at 1 kHz with ideal polarimeters.
class BenchCoreRealTime : public ::testing::Test {
 protected:
  static ScenarioConfig Scenario() {
    ScenarioConfig scenario = PaperScenario("131");
    scenario.input.disturbances[0].rate_rad_per_s = 20.0;
    scenario.simulation.polarimeter_noise_deg = 0.0;
    return scenario;
  }
  static BenchSettings Settings(double duration_s) {
    BenchSettings settings;
    settings.rate_hz = 1000.0;
    settings.duration_s = duration_s;
    return settings;
  }
  /// φ applied at `t_ns` if `motion` arrived before the sample of index `from`.
  static ControlVector ExpectedPhi(const BenchCore& bench, const WaveplateMotion& motion,
                                   int64_t from, int64_t index, int64_t t_ns) {
    if (index < from) return BuildInitialPhi(bench.scenario().controller, bench.control_count());
    ControlVector phi;
    motion.At(t_ns, &phi);
    return phi;
  }
};

/// Hands over `motion` at its `at_call`-th TakeApplied (1-based), i.e. before sample at_call − 1.
class MotionLink : public RecordingLink {
 public:
  MotionLink(WaveplateMotion motion, int at_call) : motion_(std::move(motion)), at_call_(at_call) {}
  bool TakeApplied(WaveplateMotion* motion) override {
    if (++calls_ != at_call_) return false;
    *motion = motion_;
    return true;
  }

 private:
  WaveplateMotion motion_;
  int at_call_;
  int calls_ = 0;
};

TEST_F(BenchCoreRealTime, PublishesOneSamplePerPeriodAtItsBenchTime) {
  BenchCore bench(Scenario(), Settings(0.05));
  RecordingLink link;
  const BenchReport report = bench.Run(&link, nullptr);
  EXPECT_EQ(report.stop_reason, "end of --run-s");
  EXPECT_EQ(report.samples, 50);
  EXPECT_EQ(report.published, 50);
  ASSERT_EQ(link.published.size(), 50u);
  for (size_t k = 0; k < link.published.size(); ++k) {
    EXPECT_EQ(link.published[k].sequence, k + 1);
    EXPECT_EQ(link.published[k].time_ns, static_cast<int64_t>(k) * 1'000'000);
    EXPECT_FALSE(link.published[k].lockstep);
  }
}

TEST_F(BenchCoreRealTime, TheOutputFollowsTheAppliedMotionEvaluatedAtEachSamplesTime) {
  BenchCore bench(Scenario(), Settings(0.05));
  WaveplateMotion motion = WaveplateMotion::Still(ControlVector::Constant(3, 0.1));
  motion.phi << 0.1, 0.2, 0.3;
  motion.rate_per_s << 10.0, -20.0, 5.0;
  motion.start_ns = 15'000'000;
  motion.end_ns = 30'000'000;
  motion.moving = true;
  constexpr int64_t kFrom = 9;  // handed over at the tenth sample's TakeApplied
  MotionLink link(motion, kFrom + 1);
  bench.Run(&link, nullptr);
  ASSERT_EQ(link.published.size(), 50u);

  const WaveplateChain& chain = bench.chain();
  ChainPose pose;
  for (int64_t k = 0; k < 50; ++k) {
    const BenchSample& sample = link.published[static_cast<size_t>(k)];
    chain.ComputePose(ExpectedPhi(bench, motion, kFrom, k, sample.time_ns), &pose);
    EXPECT_LT((sample.s_out - chain.Output(pose, sample.s_in)).norm(), kTolerance) << "sample " << k;
  }
  // The ramp moved φ by [0.15, −0.3, 0.075]: held at its start, S_out would be elsewhere.
  chain.ComputePose(motion.phi, &pose);
  const BenchSample& ramped = link.published[40];
  EXPECT_GT((ramped.s_out - chain.Output(pose, ramped.s_in)).norm(), 0.1);
}

TEST_F(BenchCoreRealTime, StopsAtTheFirstSampleAfterAStopRequest) {
  class StopAfterFive : public RecordingLink {
   public:
    bool stop_requested() override { return published.size() >= 5; }
  };
  BenchCore bench(Scenario(), Settings(0.0));  // until stopped
  StopAfterFive link;
  const BenchReport report = bench.Run(&link, nullptr);
  EXPECT_EQ(report.stop_reason, "stopped");
  EXPECT_EQ(report.samples, 5);
  EXPECT_EQ(report.published, 5);
  EXPECT_EQ(link.published.size(), 5u);
}

TEST(BenchCoreConstruction, AScenarioWithoutStagesThrowsScenarioError) {
  ScenarioConfig scenario = PaperScenario("131");
  scenario.stages.clear();
  EXPECT_THROW((void)BenchCore(scenario, Lockstep()), ScenarioError);
  EXPECT_THROW((void)BenchCore(scenario, BenchSettings()), ScenarioError);
}

TEST_F(BenchCoreRealTime, ARealPolarimetersReadingsArePublishedWithTheMissingSopFromTheModel) {
  // The instrument measures S_out only, and fails every fourth query with garbage.
  std::atomic<int> queries{0};
  dpc::testing::LineServer server([&](const std::string&) -> std::optional<std::string> {
    return ++queries % 4 == 0 ? std::string("#?\n") : std::string("0.000000,0.600000,0.800000\n");
  });
  PolarimeterDeviceConfig device;
  device.link.port = server.port();
  InstrumentPolarimeter polarimeter(device);
  BenchSettings settings = Settings(0.1);
  settings.settle_s = 0.0;  // statistics from the first lock on
  BenchCore bench(Scenario(), settings);
  RecordingLink link;
  std::vector<std::string> failures;
  const BenchReport report =
      bench.RunInstrument(&link, &polarimeter, nullptr, [&](const std::string& why) { failures.push_back(why); });
  EXPECT_EQ(report.stop_reason, "end of --run-s");
  EXPECT_GE(report.samples, 20);  // 100 at 1 kHz on an idle machine; fewer when it is loaded (overruns)
  EXPECT_EQ(report.published + report.failed_readings, report.samples);
  EXPECT_GE(report.failed_readings, report.samples / 4 - 1);
  ASSERT_EQ(failures.size(), static_cast<size_t>(report.failed_readings));
  EXPECT_TRUE(std::any_of(failures.begin(), failures.end(),
                          [](const std::string& why) { return why.find("not a number") != std::string::npos; }))
      << failures.front();
  ASSERT_EQ(link.published.size(), static_cast<size_t>(report.published));
  const WaveplateChain& chain = bench.chain();
  ChainPose pose;
  chain.ComputePose(BuildInitialPhi(bench.scenario().controller, bench.control_count()), &pose);
  int64_t previous_ns = -1;
  for (size_t k = 0; k < link.published.size(); ++k) {
    const BenchSample& sample = link.published[k];
    EXPECT_EQ(sample.sequence, k + 1);  // consecutive: a failed period publishes nothing
    EXPECT_GT(sample.time_ns, previous_ns);  // the reply's time
    previous_ns = sample.time_ns;
    EXPECT_TRUE(sample.s_out.isApprox(StokesVector(0, 0.6, 0.8)));
    // S_in from the model: the chain at the applied φ maps it onto the measured S_out.
    EXPECT_LT((chain.Output(pose, sample.s_in) - sample.s_out).norm(), 1e-9);
  }
  // The target is the measured output: the error is 0.
  EXPECT_NEAR(report.result.summary.error_deg.max, 0.0, 1e-3);
}

}  // namespace
}  // namespace dpc::services
