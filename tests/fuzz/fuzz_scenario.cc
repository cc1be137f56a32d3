// A scenario text through what every scenario goes through before a run: ParseScenarioText,
// ScenarioFromProto, ValidateScenario (each documents ScenarioError for a bad scenario; any
// other exception is a crash). A scenario that passes is then built as ClosedLoopSimulator
// builds it (chain, target, law timing, initial φ, the law, the disturbances): validation
// promises that a valid scenario builds.
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include <google/protobuf/stubs/logging.h>

#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_validation.h"
#include "dpc/control/control_law_factory.h"
#include "dpc/disturbance/disturbance_factory.h"
#include "dpc/scenario_io/scenario_reader.h"
#include "fuzz_support.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // Protobuf logs some parse problems (invalid UTF-8) besides reporting them; keep the output to
  // libFuzzer's.
  google::protobuf::SetLogHandler(nullptr);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dpc;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  ScenarioConfig scenario;
  try {
    scenario = ScenarioFromProto(ParseScenarioText(text, "fuzz.pbtxt"));
    ValidateScenario(scenario);
  } catch (const ScenarioError&) {
    return 0;  // refused, as documented
  }

  const int controls = ScenarioControlCount(scenario.stages);
  DPC_FUZZ_CHECK(!scenario.stages.empty() && scenario.stages.size() <= static_cast<size_t>(kMaxStages) &&
                     controls >= 1 && controls <= kMaxControls,
                 "out-of-range", "accepted %zu stages, %d controls", scenario.stages.size(), controls);
  const SimulationConfig& simulation = scenario.simulation;
  DPC_FUZZ_CHECK(std::isfinite(simulation.sample_rate_hz) && simulation.sample_rate_hz > 0.0 &&
                     simulation.sample_rate_hz <= kMaxSampleRateHz,
                 "out-of-range", "accepted sample rate %g", simulation.sample_rate_hz);
  const int64_t delay = DelaySamples(simulation);
  const int64_t total = TotalSamples(simulation);
  DPC_FUZZ_CHECK(delay >= 1 && delay <= kMaxDelaySamples, "out-of-range", "accepted a delay of %lld samples",
                 static_cast<long long>(delay));
  DPC_FUZZ_CHECK(total >= 1 && total <= kMaxTotalSamples, "out-of-range", "accepted %lld samples",
                 static_cast<long long>(total));
  DPC_FUZZ_CHECK(scenario.input.disturbances.size() <= static_cast<size_t>(kMaxDisturbances), "out-of-range",
                 "accepted %zu disturbances", scenario.input.disturbances.size());
  const StokesVector& sop = scenario.input.initial_sop;
  DPC_FUZZ_CHECK(fuzz::IsUnit(sop.x(), sop.y(), sop.z(), 1e-6), "out-of-range", "accepted initial_sop |S| = %.17g",
                 sop.norm());

  const char* step = "BuildChain";
  try {
    const WaveplateChain chain = BuildChain(scenario.stages);
    DPC_FUZZ_CHECK(chain.control_count() == controls, "contract", "chain of %d controls, counted %d",
                   chain.control_count(), controls);
    step = "BuildTarget";
    const Target target = BuildTarget(scenario.target);
    step = "BuildLawTiming";
    const LawTiming timing = BuildLawTiming(simulation);
    step = "BuildInitialPhi";
    const ControlVector phi = BuildInitialPhi(scenario.controller, controls);
    DPC_FUZZ_CHECK(phi.size() == controls && fuzz::AllFiniteVector(phi), "non-finite", "initial φ");
    step = "MakeControlLaw";
    MakeControlLaw(scenario.controller, timing, controls, target.is_point());
    step = "MakeDisturbance";
    for (const DisturbanceConfig& disturbance : scenario.input.disturbances) {
      MakeDisturbance(disturbance, simulation.sample_rate_hz);
    }
  } catch (const std::invalid_argument& e) {
    DPC_FUZZ_CHECK(false, "build", "a validated scenario fails in %s: %s", step, e.what());
  }
  return 0;
}
