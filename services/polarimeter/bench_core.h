#pragma once
// The simulated optical bench behind the polarimeter service: the input SOP (the scenario's
// disturbances), the waveplates' optics (S_out = f(φ_applied; S_in), φ_applied from the
// driver's state), the polarimeters' noise and the run statistics. Two clocks:
//
// Lockstep (simulated time). Sample k: input, plant, statistics as in `dpc sim`; from the
// activation sample on, the sample is published and the bench waits for the driver's state
// that answers it; that φ acts from sample k + D (D = the scenario's loop delay in samples),
// through the same delay line as the simulator. Same random streams, same order: a lockstep
// run across processes reproduces `dpc sim` on the same scenario and seed, trajectory for
// trajectory (tests/process). Before activation nothing is published, as in the simulator.
//
// Real time (wall clock). Every 1/rate_hz the input advances by one sample period (the
// scenario's input runs at rate_hz), S_out comes from the latest state received, and the
// sample is published; the loop delay is what the processes and DDS take. A state that
// describes a motion (a ramp, see WaveplateState) is evaluated at each sample's bench time:
// the waveplates move between states as a device that ramps its drive would.
//
// Transport-free: the service's main.cc connects it to the bus through BenchLink.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "dpc/bench/bench_messages.h"
#include "dpc/config/scenario_config.h"
#include "dpc/control/target.h"
#include "dpc/optics/waveplate_chain.h"
#include "dpc/sim/closed_loop_simulator.h"
#include "instrument_polarimeter.h"

namespace dpc::services {

/// How the bench reaches the rest of the loop.
class BenchLink {
 public:
  virtual ~BenchLink() = default;
  virtual void Publish(const BenchSample& sample) = 0;
  /// Lockstep: waits for the applied φ of the state answering `sample` (the link re-publishes
  /// the sample if no answer comes, e.g. before a controller matched). nullopt: stop (signal or
  /// timeout; `why` says which).
  virtual std::optional<ControlVector> AwaitAnswer(const BenchSample& sample, std::string* why) = 0;
  /// Real time: if a valid state (one value per control) arrived since the last call, copies
  /// the waveplates' motion it describes into `*motion` (sized for the device, so nothing is
  /// allocated) and returns true.
  virtual bool TakeApplied(WaveplateMotion* motion) = 0;
  /// Real time: the latest accepted target, if it changed since the last call.
  virtual std::optional<TargetConfig> TargetChange() = 0;
  virtual bool stop_requested() = 0;
};

struct BenchSettings {
  bool lockstep = false;
  double rate_hz = 10e3;           ///< real time
  double duration_s = 0.0;         ///< real time: 0 runs until stopped
  double settle_s = 0.5;           ///< real time: statistics from this long after the first lock
  /// Lockstep: called every 1024 samples with the samples done and the run's total.
  std::function<void(int64_t done, int64_t total)> lockstep_progress;
};

struct BenchReport {
  SimulationResult result;
  int64_t failed_readings = 0;     ///< a real polarimeter: periods without a reading
  int64_t samples = 0;
  int64_t published = 0;
  int64_t overruns = 0;            ///< real time: sample periods the loop came late for
  double achieved_rate_hz = 0.0;
  std::string stop_reason;
};

class BenchCore {
 public:
  /// `scenario` is validated here (ValidateScenario). Throws ScenarioError.
  BenchCore(ScenarioConfig scenario, BenchSettings settings);
  ~BenchCore();

  /// Runs until the scenario's duration (lockstep), --duration-s (real time) or a stop.
  /// `observer` gets every sample (traces) and progress, as in ClosedLoopSimulator::Run.
  BenchReport Run(BenchLink* link, SimulationObserver* observer);

  /// Real time with a real polarimeter instead of the simulated optics: every 1/rate_hz one
  /// reading, published with the time its reply arrived; what the instrument does not measure
  /// (S_in or S_out) comes from the model, the chain at the applied φ (S_out = M·S_in,
  /// S_in = Mᵀ·S_out). A period without a reading publishes nothing; `on_failure` gets why
  /// (from the bench's thread). The statistics are of the measured (or modelled) S_out.
  BenchReport RunInstrument(BenchLink* link, InstrumentPolarimeter* polarimeter, SimulationObserver* observer,
                            const std::function<void(const std::string&)>& on_failure);

  const ScenarioConfig& scenario() const { return scenario_; }
  const WaveplateChain& chain() const { return *chain_; }
  const Target& target() const { return *target_; }
  int control_count() const { return chain_->control_count(); }

 private:
  BenchReport RunLockstep(BenchLink* link, SimulationObserver* observer);
  BenchReport RunRealTime(BenchLink* link, SimulationObserver* observer);
  BenchSample MakeSample(uint64_t sequence, int64_t sample_time_ns, const StokesVector& s_in,
                         const StokesVector& s_out) const;

  ScenarioConfig scenario_;
  BenchSettings settings_;
  std::unique_ptr<WaveplateChain> chain_;
  std::unique_ptr<Target> target_;
  ControlVector initial_phi_;
};

}  // namespace dpc::services
