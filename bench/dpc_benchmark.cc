// Speed of the core: one control update per law (3 and 4 stages), the kinematics, and the
// closed-loop simulator, each next to a straightforward baseline that computes J⁺ with Eigen's
// JacobiSVD. Run: build/bench/dpc_benchmark   (Google Benchmark flags work, e.g.
// --benchmark_filter=Law). After the usual table it prints a summary with the ratios to the
// SVD baseline, the goals from the core issue (GP update ≤ 100 ns, simulator ≥ 10 M samples/s)
// and, side by side, those of "Speed at the machine's limit": the full control update
// (ControlLoop/gp: pose, kinematics, task, law) ≤ 40 ns for 4 stages (must ≤ 50), ≤ 30 ns for 3,
// one trajectory (Simulator/gp) ≥ 25 M samples/s for 4 stages (must ≥ 20 M), batches in SIMD
// lanes on one core (Simulator/batch-avx2 ≥ 60 M, Simulator/batch-avx512 ≥ 100 M) and a sweep on
// every core (Sweep/all-cores, wall time, ≥ 180 M). Both ControlLoop/gp and ControlLoop/gp-general
// and the simulator with its general loop print there, and a batch's time split into its kernel
// alone (BatchKernel) and the rest.

#include <Eigen/SVD>
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <map>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "dpc/config/scenario_config.h"
#include "dpc/control/control_law_factory.h"
#include "dpc/control/control_problem.h"
#include "dpc/control/gradient_projection_law.h"
#include "dpc/control/polarization_controller.h"
#include "dpc/sim/batch_simulator.h"
#include "dpc/sim/closed_loop_simulator.h"
#include "dpc/sim/run_statistics.h"
#include "dpc/sim/sweep_runner.h"

namespace dpc {
namespace {

const Target kPaperTarget = Target::Point(StokesVector(0, 0.6, 0.8));

// The baseline: gradient projection with J⁺ from a JacobiSVD of the full 3 × n Jacobian, as a
// straightforward implementation of paper eq. 10 would do it.
class SvdGradientProjectionLaw final : public ControlLaw {
 public:
  SvdGradientProjectionLaw(double step, double nullspace_step)
      : step_(step), nullspace_step_(nullspace_step) {}

  ControlStatus ComputeUpdate(const ControlProblem& p, ControlVector* delta_phi) override {
    const Eigen::MatrixXd j = p.kinematics.jacobian;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(j, Eigen::ComputeThinU | Eigen::ComputeThinV);
    svd.setThreshold(1e-12);
    const Eigen::VectorXd error = p.PointError();
    const Eigen::VectorXd phi = p.phi();
    const Eigen::VectorXd task = svd.solve(error);
    const Eigen::VectorXd null = phi - svd.solve(j * phi);
    *delta_phi = step_ * task - nullspace_step_ * null;
    diagnostics_.nullspace_active = true;
    return ControlStatus::kOk;
  }
  std::string_view name() const override { return "gp-svd"; }

 private:
  double step_, nullspace_step_;
};

std::unique_ptr<ControlLaw> MakeSvdBaseline(const ControllerConfig& c, const LawTiming&, int, bool) {
  return std::make_unique<SvdGradientProjectionLaw>(c.step, c.nullspace_step);
}

// A pool of prepared control problems (random φ and S_in) so each iteration sees a new one.
class ProblemPool {
 public:
  explicit ProblemPool(const std::string& axes, int size = 1024)
      : chain_(WaveplateChain::FromAxes(axes)), poses_(size), problems_(size) {
    std::mt19937_64 rng(3);
    std::normal_distribution<double> normal;
    for (int i = 0; i < size; ++i) {
      ControlVector phi(chain_.control_count());
      for (int c = 0; c < phi.size(); ++c) phi[c] = 0.8 * normal(rng);
      chain_.ComputePose(phi, &poses_[i]);
      ControlProblem& p = problems_[i];
      p.chain = &chain_;
      p.target = &kPaperTarget;
      p.pose = &poses_[i];
      p.s_in = StokesVector(normal(rng), normal(rng), normal(rng)).normalized();
      p.s_out_measured = chain_.Output(poses_[i], p.s_in);
      UpdateControlProblem(&p);
    }
  }
  const WaveplateChain& chain() const { return chain_; }
  std::vector<ChainPose>& poses() { return poses_; }
  std::vector<ControlProblem>& problems() { return problems_; }

 private:
  WaveplateChain chain_;
  std::vector<ChainPose> poses_;
  std::vector<ControlProblem> problems_;
};

std::string Axes(int stages) { return stages == 3 ? "131" : "3131"; }

// One law's update on prepared problems: the time a controller spends in the law.
void BM_LawUpdate(benchmark::State& state, ControlMethod method) {
  const int stages = static_cast<int>(state.range(0));
  ProblemPool pool(Axes(stages));
  ControllerConfig config;
  config.method = method;
  std::unique_ptr<ControlLaw> law = method == ControlMethod::kGradientProjection && state.range(1)
                                        ? MakeSvdBaseline(config, LawTiming{}, stages, true)
                                        : MakeControlLaw(config, LawTiming{}, stages, true);
  ControlVector delta;
  auto& problems = pool.problems();
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(law->ComputeUpdate(problems[i], &delta));
    benchmark::DoNotOptimize(delta.data());
    if (++i == problems.size()) i = 0;
  }
}

// What a controller does per sample: pose of the new command, kinematics and task, the law.
void BM_FullControlStep(benchmark::State& state) {
  const int stages = static_cast<int>(state.range(0));
  const bool svd = state.range(1) != 0;
  ProblemPool pool(Axes(stages));
  ControllerConfig config;
  std::unique_ptr<ControlLaw> law = svd ? MakeSvdBaseline(config, LawTiming{}, stages, true)
                                        : MakeControlLaw(config, LawTiming{}, stages, true);
  ControlVector delta;
  ChainPose pose;
  auto& problems = pool.problems();
  size_t i = 0;
  for (auto _ : state) {
    ControlProblem& p = problems[i];
    pool.chain().ComputePose(p.pose->phi, &pose);
    p.pose = &pose;
    UpdateControlProblem(&p);
    benchmark::DoNotOptimize(law->ComputeUpdate(p, &delta));
    p.pose = &pool.poses()[i];
    if (++i == problems.size()) i = 0;
  }
}

// What a control update adds in the loop (BM_ControlLoop's second argument).
enum LoopVariant : int64_t {
  kPlain = 0,       // the paper's gradient projection (the fused update)
  kPredict = 1,     // + delay compensation (predictor, aim, lead)
  kCorrect = 2,     // + delay compensation and the curvature correction
  kDamped = 3,      // singularity-robust damping only
  kRange = 4,       // range criterion with saturate-and-re-solve only (ranges ±1)
  kGeneral = 5,     // the paper's gradient projection on the general path (a law factory)
};

WaveplateChain LoopChain(int stages, bool ranges) {
  if (!ranges) return WaveplateChain::FromAxes(Axes(stages));
  std::vector<WaveplateStage> list;
  for (char c : Axes(stages)) {
    list.push_back(WaveplateStage::FixedAxis(c == '1' ? Vector3::UnitX() : Vector3::UnitZ(),
                                             ControlMap::Linear(M_PI), ControlRange{-1.0, 1.0}));
  }
  return WaveplateChain(std::move(list));
}

// A full control update (pose, chain kinematics, task, law, integration) in the controller's
// dependent chain, each update at the previous one's command. The paper's gp runs the fused
// update, which keeps the pose of its command (PolarizationController::Update(input)); the
// general path (options, kGeneral) as the simulator's general loop runs it: Update on the pose
// of the current command, then the new command's pose derived from it (incremental
// sines/cosines).
void BM_ControlLoop(benchmark::State& state) {
  const int stages = static_cast<int>(state.range(0));
  const int64_t variant = state.range(1);
  const WaveplateChain chain = LoopChain(stages, variant == kRange);
  ControllerConfig config;
  config.curvature_correction = variant == kCorrect;
  if (variant == kDamped) config.singularity_damping = SingularityDampingConfig{0.25, 0.5};
  if (variant == kRange) config.nullspace_criterion = NullspaceCriterion::kRange;
  if (variant == kPredict || variant == kCorrect) config.prediction = PredictionConfig{};  // window 1000
  PolarizationController controller(chain, kPaperTarget, config, LawTiming{50e6, 50},
                                    ControlVector::Constant(stages, 0.3),
                                    variant == kGeneral ? MakeControlLaw : nullptr);
  // A slowly rotating input keeps the loop tracking (the steps stay small, as in the scenario).
  const Matrix3 turn = RotationAboutAxis(Vector3::UnitZ(), 2e-3);
  ControlInput input;
  input.s_in = StokesVector(0.3, -0.5, 0.81).normalized();
  if (controller.fused()) {
    for (auto _ : state) {
      input.s_in = turn * input.s_in;
      controller.Update(input);
    }
  } else {
    ChainPose poses[2];
    chain.ComputePose(controller.phi(), &poses[0]);
    int current = 0;
    for (auto _ : state) {
      input.s_in = turn * input.s_in;
      controller.Update(input, poses[current]);
      chain.ComputePoseFrom(poses[current], controller.phi(), &poses[1 - current]);
      current = 1 - current;
    }
  }
  state.SetLabel(controller.fused() ? "fused" : "general");
  benchmark::DoNotOptimize(controller.phi().data());
}

void BM_Kinematics(benchmark::State& state) {
  ProblemPool pool(Axes(static_cast<int>(state.range(0))));
  ChainKinematics k;
  auto& problems = pool.problems();
  size_t i = 0;
  for (auto _ : state) {
    pool.chain().Evaluate(*problems[i].pose, problems[i].s_in, &k);
    benchmark::DoNotOptimize(k.jacobian.data());
    if (++i == problems.size()) i = 0;
  }
}

void BM_ComputePose(benchmark::State& state) {
  ProblemPool pool(Axes(static_cast<int>(state.range(0))));
  ChainPose pose;
  auto& problems = pool.problems();
  size_t i = 0;
  for (auto _ : state) {
    pool.chain().ComputePose(problems[i].pose->phi, &pose);
    benchmark::DoNotOptimize(pose.cos.data());
    if (++i == problems.size()) i = 0;
  }
}

// The paper scenario in the simulator; reports samples per second. Variant 0: as `dpc sim` runs
// it (the fast path); 1: the SVD baseline law (general loop); 2: the built-in law through the
// general loop (a user-supplied factory keeps the simulator off the fast path).
void BM_Simulator(benchmark::State& state) {
  const int stages = static_cast<int>(state.range(0));
  const int64_t variant = state.range(1);
  ScenarioConfig scenario = PaperScenario(Axes(stages));
  scenario.simulation.duration_s = 0.02;  // 1e6 samples at 50 MHz
  scenario.controller.activation_s = 0.0;
  ControlLawFactory factory = nullptr;
  if (variant == 1) factory = MakeSvdBaseline;
  if (variant == 2) {
    factory = [](const ControllerConfig& c, const LawTiming& timing, int n, bool point) {
      return MakeControlLaw(c, timing, n, point);
    };
  }
  ClosedLoopSimulator simulator(scenario, factory);
  int64_t samples = 0;
  for (auto _ : state) {
    const SimulationResult r = simulator.Run();
    samples += r.summary.samples;
    benchmark::DoNotOptimize(r.summary.error_deg.mean);
  }
  state.counters["samples_per_s"] =
      benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
}

// Batches of the paper scenario (one seed per lane) on one core; reports samples per second of
// all lanes together. Arg 1: the instruction set (1 AVX2, 2 AVX-512). `parts`: the whole run, or
// the kernel alone (BatchParts::kKernelOnly: no statistics, no normal draws after the first block).
void RunSimulatorBatch(benchmark::State& state, BatchParts parts) {
  const int stages = static_cast<int>(state.range(0));
  const BatchIsa isa = state.range(1) == 2 ? BatchIsa::kAvx512 : BatchIsa::kAvx2;
  if (DetectBatchIsa() < isa) {
    state.SkipWithError("the processor lacks this instruction set");
    return;
  }
  std::vector<std::unique_ptr<ClosedLoopSimulator>> simulators;
  std::vector<const ClosedLoopSimulator*> lanes;
  for (int l = 0; l < BatchLanesOf(isa); ++l) {
    ScenarioConfig scenario = PaperScenario(Axes(stages));
    scenario.simulation.duration_s = 0.02;  // 1e6 samples per lane at 50 MHz
    scenario.controller.activation_s = 0.0;
    scenario.simulation.seed = static_cast<uint64_t>(l + 1);
    simulators.push_back(std::make_unique<ClosedLoopSimulator>(scenario));
    lanes.push_back(simulators.back().get());
  }
  int64_t samples = 0;
  for (auto _ : state) {
    const std::vector<SimulationResult> results = RunBatch(lanes, isa, parts);
    for (const SimulationResult& r : results) samples += r.summary.samples;
    benchmark::DoNotOptimize(results.front().final_phi[0]);
  }
  state.counters["samples_per_s"] =
      benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
}
void BM_SimulatorBatch(benchmark::State& state) { RunSimulatorBatch(state, BatchParts::kAll); }
void BM_BatchKernel(benchmark::State& state) { RunSimulatorBatch(state, BatchParts::kKernelOnly); }

// The simulator's statistics alone (RunStatistics::AddSample and its batched Flush), in samples
// per second: a locked output wandering ~0.1° around the paper's target and `controls` slowly
// drifting controls, as the paper scenario feeds them.
void BM_Statistics(benchmark::State& state) {
  const int controls = static_cast<int>(state.range(0));
  constexpr int kSamples = 1 << 16;
  std::mt19937_64 engine(7);
  std::normal_distribution<double> normal(0.0, 1e-3);  // rad, per component of S_out
  std::vector<StokesVector> outputs(kSamples);
  std::vector<double> phi(static_cast<size_t>(kSamples) * controls);
  double drift[8] = {0.3, -0.7, 1.1, 0.2, 0.5, -0.4, 0.9, 0.6};
  for (int i = 0; i < kSamples; ++i) {
    outputs[i] = (kPaperTarget.point() + StokesVector(normal(engine), normal(engine),
                                                      normal(engine))).normalized();
    for (int c = 0; c < controls; ++c) {
      drift[c] += 0.1 * normal(engine);  // steps of 1e-4 RMS
      phi[static_cast<size_t>(i) * controls + c] = drift[c];
    }
  }
  RunStatistics statistics(kPaperTarget, controls, 0.0, 1.0, std::nullopt);
  int64_t samples = 0;
  for (auto _ : state) {
    for (int i = 0; i < kSamples; ++i) {
      statistics.AddSample(static_cast<double>(samples + i) * 2e-8, outputs[i],
                           phi.data() + static_cast<size_t>(i) * controls);
    }
    samples += kSamples;
  }
  benchmark::DoNotOptimize(statistics.Summarize(samples, 0).error_deg.mean);
  state.counters["samples_per_s"] =
      benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
}

// A sweep as `dpc sweep` runs it (RunSweep: batches in the widest lanes, on every core): 4 seeds
// per core and lane of the paper scenario; samples per second of wall time.
void BM_Sweep(benchmark::State& state) {
  const int stages = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<ScenarioConfig> scenarios;
  for (int i = 0; i < 4 * threads * BatchLanesOf(ChosenBatchIsa()); ++i) {
    ScenarioConfig scenario = PaperScenario(Axes(stages));
    scenario.simulation.duration_s = 0.01;
    scenario.controller.activation_s = 0.0;
    scenario.simulation.seed = static_cast<uint64_t>(i + 1);
    scenarios.push_back(scenario);
  }
  int64_t samples = 0;
  for (auto _ : state) {
    const std::vector<SweepOutcome> outcomes = RunSweep(scenarios, threads);
    for (const SweepOutcome& o : outcomes) samples += o.result.summary.samples;
  }
  state.counters["samples_per_s"] =
      benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
}

void RegisterAll() {
  const std::vector<std::pair<const char*, ControlMethod>> laws{
      {"transpose", ControlMethod::kTranspose},
      {"pinv", ControlMethod::kPseudoInverse},
      {"rls", ControlMethod::kRegularizedLeastSquares},
      {"gp", ControlMethod::kGradientProjection},
      {"gpt", ControlMethod::kThresholdedGradientProjection},
      {"extended", ControlMethod::kExtendedJacobian},
      {"dither", ControlMethod::kDither},
  };
  for (const auto& [name, method] : laws) {
    benchmark::RegisterBenchmark(fmt::format("Law/{}", name).c_str(), BM_LawUpdate, method)
        ->Args({3, 0})
        ->Args({4, 0});
  }
  for (const auto& [name, method] :
       std::vector<std::pair<const char*, ControlMethod>>{{"inverse", ControlMethod::kInverse},
                                                          {"damped", ControlMethod::kDamped}}) {
    benchmark::RegisterBenchmark(fmt::format("Law/{}", name).c_str(), BM_LawUpdate, method)
        ->Args({3, 0});
  }
  benchmark::RegisterBenchmark("Law/gp-svd-baseline", BM_LawUpdate,
                               ControlMethod::kGradientProjection)
      ->Args({3, 1})
      ->Args({4, 1});
  benchmark::RegisterBenchmark("ComputePose", BM_ComputePose)->Arg(3)->Arg(4);
  benchmark::RegisterBenchmark("Kinematics", BM_Kinematics)->Arg(3)->Arg(4);
  for (const auto& [name, variant] : std::vector<std::pair<const char*, int64_t>>{
           {"ControlLoop/gp", kPlain},
           {"ControlLoop/gp-general", kGeneral},
           {"ControlLoop/gp-predict", kPredict},
           {"ControlLoop/gp-predict-correct", kCorrect},
           {"ControlLoop/gp-damped", kDamped},
           {"ControlLoop/gp-range", kRange}}) {
    benchmark::RegisterBenchmark(name, BM_ControlLoop)->Args({3, variant})->Args({4, variant});
  }
  benchmark::RegisterBenchmark("ControlStep/gp", BM_FullControlStep)->Args({3, 0})->Args({4, 0});
  benchmark::RegisterBenchmark("ControlStep/gp-svd-baseline", BM_FullControlStep)
      ->Args({3, 1})
      ->Args({4, 1});
  benchmark::RegisterBenchmark("Simulator/gp", BM_Simulator)
      ->Args({3, 0})
      ->Args({4, 0})
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("Simulator/gp-svd-baseline", BM_Simulator)
      ->Args({3, 1})
      ->Args({4, 1})
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("Simulator/gp-general-loop", BM_Simulator)
      ->Args({3, 2})
      ->Args({4, 2})
      ->Unit(benchmark::kMillisecond);
  // A batch and its kernel alone, per instruction set (arg 1: 1 AVX2, 2 AVX-512).
  using Function = void (*)(benchmark::State&);
  for (const auto& [prefix, function] : {std::pair<const char*, Function>{"Simulator/batch-", BM_SimulatorBatch},
                                         std::pair<const char*, Function>{"BatchKernel/", BM_BatchKernel}}) {
    for (const auto& [isa, arg] : {std::pair{"avx2", 1}, std::pair{"avx512", 2}}) {
      benchmark::RegisterBenchmark((std::string(prefix) + isa).c_str(), function)
          ->Args({3, arg})
          ->Args({4, arg})
          ->Unit(benchmark::kMillisecond);
    }
  }
  benchmark::RegisterBenchmark("Statistics", BM_Statistics)->Arg(3)->Arg(4);
  benchmark::RegisterBenchmark("Sweep/all-cores", BM_Sweep)
      ->Arg(3)
      ->Arg(4)
      ->UseRealTime()
      ->Unit(benchmark::kMillisecond);
}

// Collects every run for the summary while the console reporter prints as usual: with
// --benchmark_repetitions the median of the repetitions (also under
// --benchmark_report_aggregates_only), otherwise the one run. The summary takes CPU time (as the
// samples/s counters do): on the shared 2-core VM wall time also counts the other processes'
// turns.
class CollectingReporter : public benchmark::ConsoleReporter {
 public:
  struct Entry {
    double ns_per_iteration;
    double samples_per_s;
  };
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      const bool median = run.run_type == Run::RT_Aggregate && run.aggregate_name == "median";
      const std::string name = run.run_name.str();
      if (median) {
        medians_.insert(name);
      } else if (run.run_type != Run::RT_Iteration || medians_.count(name) != 0) {
        continue;
      }
      Entry e{run.GetAdjustedCPUTime() * NanosecondsPer(run.time_unit), 0.0};
      if (auto it = run.counters.find("samples_per_s"); it != run.counters.end()) {
        e.samples_per_s = it->second.value;
      }
      entries[name] = e;
    }
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, Entry> entries;

 private:
  std::set<std::string> medians_;

  static double NanosecondsPer(benchmark::TimeUnit unit) {
    switch (unit) {
      case benchmark::kNanosecond: return 1.0;
      case benchmark::kMicrosecond: return 1e3;
      case benchmark::kMillisecond: return 1e6;
      case benchmark::kSecond: return 1e9;
    }
    return 1.0;
  }
};

void PrintSummary(const std::map<std::string, CollectingReporter::Entry>& e) {
  const auto find = [&](const std::string& name) -> const CollectingReporter::Entry* {
    auto it = e.find(name);
    return it == e.end() ? nullptr : &it->second;
  };
  fmt::print("\nSummary (per-update CPU times; ratio = SVD baseline / this)\n");
  fmt::print("{:<22} {:>7} {:>12} {:>16} {:>8}\n", "law", "stages", "ns/update", "svd-baseline ns",
             "ratio");
  for (const char* law :
       {"inverse", "transpose", "damped", "pinv", "rls", "gp", "gpt", "extended", "dither"}) {
    for (int stages : {3, 4}) {
      const auto* x = find(fmt::format("Law/{}/{}/0", law, stages));
      const auto* base = find(fmt::format("Law/gp-svd-baseline/{}/1", stages));
      if (!x || !base) continue;
      fmt::print("{:<22} {:>7} {:>12.1f} {:>16.1f} {:>7.1f}x\n", law, stages, x->ns_per_iteration,
                 base->ns_per_iteration, base->ns_per_iteration / x->ns_per_iteration);
    }
  }
  for (int stages : {3, 4}) {
    const auto* x = find(fmt::format("ControlStep/gp/{}/0", stages));
    const auto* base = find(fmt::format("ControlStep/gp-svd-baseline/{}/1", stages));
    if (!x || !base) continue;
    fmt::print("{:<22} {:>7} {:>12.1f} {:>16.1f} {:>7.1f}x   (pose + kinematics + task + law)\n",
               "control step (gp)", stages, x->ns_per_iteration, base->ns_per_iteration,
               base->ns_per_iteration / x->ns_per_iteration);
  }
  fmt::print("\nControl update in the loop (pose + kinematics + task + law), the options (general\n"
             "path) against plain gp on the general path\n");
  fmt::print("{:<32} {:>7} {:>12} {:>12} {:>8}\n", "variant", "stages", "ns/update", "plain ns",
             "added");
  for (int stages : {3, 4}) {
    const auto* plain = find(fmt::format("ControlLoop/gp-general/{}/5", stages));
    for (const auto& [name, variant] :
         {std::pair{"gp-predict", 1}, std::pair{"gp-predict-correct", 2},
          std::pair{"gp-damped", 3}, std::pair{"gp-range", 4}}) {
      const auto* x = find(fmt::format("ControlLoop/{}/{}/{}", name, stages, variant));
      if (!x || !plain) continue;
      const double added = x->ns_per_iteration / plain->ns_per_iteration - 1.0;
      fmt::print("{:<32} {:>7} {:>12.1f} {:>12.1f} {:>+7.0f}%{}\n", name, stages,
                 x->ns_per_iteration, plain->ns_per_iteration, 100.0 * added,
                 variant == 1 ? (added <= 0.30 ? "   goal <= +30%: MET" : "   goal <= +30%: MISSED")
                              : "");
    }
  }
  fmt::print("\n{:<22} {:>7} {:>18} {:>22} {:>8}\n", "simulator", "stages", "M samples/s",
             "svd-baseline M samples/s", "ratio");
  for (int stages : {3, 4}) {
    const auto* base = find(fmt::format("Simulator/gp-svd-baseline/{}/1", stages));
    for (const auto& [name, label] :
         {std::pair{"Simulator/gp/{}/0", "paper scenario, gp"},
          std::pair{"Simulator/gp-general-loop/{}/2", "  (general loop)"}}) {
      const auto* x = find(fmt::format(fmt::runtime(name), stages));
      if (!x || !base) continue;
      fmt::print("{:<22} {:>7} {:>18.2f} {:>22.2f} {:>7.1f}x\n", label, stages,
                 x->samples_per_s / 1e6, base->samples_per_s / 1e6,
                 x->samples_per_s / base->samples_per_s);
    }
  }
  const auto* gp4 = find("Law/gp/4/0");
  const auto sim_goal = [&](int stages) {
    const auto* sim = find(fmt::format("Simulator/gp/{}/0", stages));
    return sim ? fmt::format("{} stages {:.2f} M samples/s {}", stages, sim->samples_per_s / 1e6,
                             sim->samples_per_s >= 1e7 ? "MET" : "MISSED")
               : fmt::format("{} stages not run", stages);
  };
  fmt::print("\nGoals: 4-stage gp update <= 100 ns (aim 20 ns): {}\n",
             gp4 ? fmt::format("{:.1f} ns {}", gp4->ns_per_iteration,
                               gp4->ns_per_iteration <= 100 ? "MET" : "MISSED")
                 : "not run");
  fmt::print("       paper simulation >= 10 M samples/s on one core (aim 50 M): {}; {}\n",
             sim_goal(3), sim_goal(4));

  // Issue "Speed at the machine's limit": the full control update (ControlLoop/gp: pose,
  // kinematics, task, law, integration) and one trajectory (Simulator/gp), side by side.
  const auto verdict = [](double value, double goal, double must, bool at_most) {
    const auto meets = [&](double bound) { return at_most ? value <= bound : value >= bound; };
    return meets(goal) ? "goal MET" : meets(must) ? "goal missed, must MET" : "MISSED";
  };
  fmt::print("\nGoals at the machine's limit (general path beside)\n");
  for (const auto& [stages, goal, must] : {std::tuple{4, 40.0, 50.0}, std::tuple{3, 30.0, 30.0}}) {
    const auto* x = find(fmt::format("ControlLoop/gp/{}/0", stages));
    const auto* general = find(fmt::format("ControlLoop/gp-general/{}/5", stages));
    if (!x) continue;
    fmt::print("  full control update, gp, {} stages: {:6.1f} ns{}   "
               "<= {:.0f} ns{}: {}\n",
               stages, x->ns_per_iteration,
               general ? fmt::format(" ({:.1f} ns general)", general->ns_per_iteration) : std::string(), goal,
               must > goal ? fmt::format(" (must <= {:.0f})", must) : "",
               verdict(x->ns_per_iteration, goal, must, true));
  }
  for (int stages : {4, 3}) {
    const auto* sim = find(fmt::format("Simulator/gp/{}/0", stages));
    const auto* general = find(fmt::format("Simulator/gp-general-loop/{}/2", stages));
    if (!sim) continue;
    fmt::print("  one trajectory, {} stages:          {:6.2f} M samples/s{}{}\n", stages, sim->samples_per_s / 1e6,
               general ? fmt::format(" ({:.2f} M general loop)", general->samples_per_s / 1e6) : std::string(),
               stages == 4 ? fmt::format("   >= 25 M (must >= 20 M): {}",
                                         verdict(sim->samples_per_s, 25e6, 20e6, false))
                           : "");
  }
  // Where a sample of one trajectory goes: the update's dependency chain, the statistics (their
  // benchmark alone), and the rest (input, plant, what did not overlap).
  for (int stages : {4, 3}) {
    const auto* sim = find(fmt::format("Simulator/gp/{}/0", stages));
    const auto* update = find(fmt::format("ControlLoop/gp/{}/0", stages));
    const auto* statistics = find(fmt::format("Statistics/{}", stages));
    if (!sim || !update || !statistics || sim->samples_per_s <= 0 || statistics->samples_per_s <= 0) {
      continue;
    }
    const double sample_ns = 1e9 / sim->samples_per_s;
    const double statistics_ns = 1e9 / statistics->samples_per_s;
    fmt::print("  a sample of one trajectory, {} stages: {:.1f} ns = update {:.1f} ns + statistics "
               "{:.1f} ns (alone) + the rest {:.1f} ns\n",
               stages, sample_ns, update->ns_per_iteration, statistics_ns,
               sample_ns - update->ns_per_iteration - statistics_ns);
  }
  for (int stages : {4, 3}) {
    const auto* sim = find(fmt::format("Simulator/gp/{}/0", stages));
    for (const auto& [isa, arg, goal] : {std::tuple{"avx2", 1, 60e6}, std::tuple{"avx512", 2, 100e6}}) {
      const auto* batch = find(fmt::format("Simulator/batch-{}/{}/{}", isa, stages, arg));
      if (!batch || batch->samples_per_s <= 0.0) continue;
      fmt::print("  batched ({:<6}) one core, {} stages: {:6.2f} M samples/s{}{}\n", isa, stages,
                 batch->samples_per_s / 1e6,
                 sim && sim->samples_per_s > 0.0
                     ? fmt::format(" ({:.2f}x one trajectory)", batch->samples_per_s / sim->samples_per_s)
                     : std::string(" (one trajectory not run: --benchmark_filter)"),
                 stages == 4 ? fmt::format("   >= {:.0f} M: {}", goal / 1e6,
                                           verdict(batch->samples_per_s, goal, goal, false))
                             : "");
    }
  }
  for (int stages : {4, 3}) {
    // Each lane keeps its own statistics, fed sample by sample: they alone bound a batch.
    const auto* statistics = find(fmt::format("Statistics/{}", stages));
    if (!statistics || statistics->samples_per_s <= 0) continue;
    fmt::print("  the statistics alone, {} stages:   {:6.2f} M samples/s on one core (the most any "
               "batch can reach)\n",
               stages, statistics->samples_per_s / 1e6);
  }
  // A batch's time split in two: the kernel alone (BatchParts::kKernelOnly) and the rest (the
  // lanes' normal draws, statistics and update tallies), in ns per trajectory-sample, beside what
  // the goal leaves the rest.
  for (int stages : {4, 3}) {
    for (const auto& [isa, arg, goal] : {std::tuple{"avx2", 1, 60e6}, std::tuple{"avx512", 2, 100e6}}) {
      const auto* batch = find(fmt::format("Simulator/batch-{}/{}/{}", isa, stages, arg));
      const auto* kernel = find(fmt::format("BatchKernel/{}/{}/{}", isa, stages, arg));
      if (!batch || !kernel || batch->samples_per_s <= 0 || kernel->samples_per_s <= 0) continue;
      const double kernel_ns = 1e9 / kernel->samples_per_s, batch_ns = 1e9 / batch->samples_per_s;
      fmt::print("  {:<6} batch, {} stages: {:.2f} ns a trajectory-sample = the kernel alone {:.2f} ns "
                 "({:.1f} M/s) + the rest {:.2f} ns{}\n",
                 isa, stages, batch_ns, kernel_ns, kernel->samples_per_s / 1e6, batch_ns - kernel_ns,
                 stages == 4 ? fmt::format("; >= {:.0f} M leaves the rest {:.2f} ns", goal / 1e6,
                                           1e9 / goal - kernel_ns)
                             : "");
    }
  }
  for (int stages : {4, 3}) {
    const auto* sweep = find(fmt::format("Sweep/all-cores/{}/real_time", stages));
    if (!sweep) continue;
    fmt::print("  sweep on every core ({} lanes), {} stages: {:6.2f} M samples/s{}\n",
               BatchIsaName(ChosenBatchIsa()), stages, sweep->samples_per_s / 1e6,
               stages == 4 ? fmt::format("   >= 180 M: {}",
                                         verdict(sweep->samples_per_s, 180e6, 180e6, false))
                           : "");
  }
}

}  // namespace
}  // namespace dpc

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  dpc::RegisterAll();
  dpc::CollectingReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  dpc::PrintSummary(reporter.entries);
  benchmark::Shutdown();
  return 0;
}
