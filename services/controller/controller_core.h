#pragma once
// The controller service's logic, without DDS. The wiring (main.cc) feeds it what arrives and
// publishes what it returns, under one lock. The control step itself is the
// PolarizationController's (control/polarization_controller.h), the same as the simulator's;
// this class adds what the bench needs around it: configuration from the bus, following the
// driver's state, the measured loop latency, commands and status.
//
// Configuration comes from the bus: the device description (TRANSIENT_LOCAL, from the driver)
// builds the chain, the target topic the target; the law and its settings come from the
// scenario's controller section and flags. Until the device, the target and a driver state have
// arrived the controller answers nothing (status says what it waits for).
//
// Bumpless joining and switching: while the driver obeys another controller (or holds), this
// one follows the applied φ from the driver's state: its integrator is reset to phi_applied of
// every state (see OnState for the one exception). Its commands are then "applied φ + Δφ", so
// the moment the driver obeys it nothing jumps. Once obeyed, it
// integrates its own commands (paper eq. 6), as `dpc sim` does; if the driver reports that it
// limited this controller's latest command, the integrator takes the applied φ (no wind-up).
//
// Delay compensation (scenario controller.prediction, flag --predict; delay_compensator.h):
// the law aims at the input SOP predicted for the moment its command acts. In real time that
// horizon is measured, not configured: when sample j arrives, the latest state this controller
// has seen answers sample a (the command the polarimeter applied when it measured j, within a
// state's transit), so a command computed now acts ≈ t_j − t_a later (sample timestamps). The
// horizon is that latency, smoothed over ~64 samples; a configured horizon_samples (in periods
// of the scenario's sample_rate_hz) replaces it, and so does the lockstep bench's own delay.
// Samples are observed at their timestamps (InputPredictor::ObserveAt), so a real-time
// polarimeter's jitter does not bias the fitted rotation.
//
// That is PredictionMode::kLatency. The default in real time, kRamp, does better: a single
// horizon cannot fit a latency that jitters by a sample or two, so the command carries the
// motion instead of a point: φ at the sample's time plus φ̇, the rate that keeps the output still
// while the input turns at the fitted rate (PolarizationController, rate commands); the driver
// moves the waveplates along φ + φ̇·(t − t_sample) in bench time, so wherever the command lands
// in time it is right for that moment. Before each update the command advances along its
// latest ramp (the waveplates followed it); a standby controller follows the applied motion
// evaluated at each sample's time. Lockstep samples get no rate (the simulated bench's delay
// line applies points), so lockstep still equals `dpc sim`.
//
// When samples stop, nothing is integrated (the controller only acts on samples): the
// integrator is frozen, the status says "frozen", and after a gap longer than freeze_after_s the
// controller re-joins from the applied φ when samples resume.

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "dpc/bench/bench_messages.h"
#include "dpc/config/scenario_config.h"
#include "dpc/control/polarization_controller.h"
#include "dpc/control/target.h"
#include "dpc/optics/waveplate_chain.h"

namespace dpc::services {

/// How a predicting controller (controller.prediction set) compensates the real-time loop delay.
enum class PredictionMode {
  kRamp,     ///< commands carry φ̇ from the fitted input rotation; the driver ramps (default)
  kLatency,  ///< the law aims at the input predicted across the measured latency (a point)
};

struct ControllerSettings {
  std::string controller_id = "controller";
  int32_t priority = 0;
  ControllerConfig controller;      ///< law, step, loop mode (scenario's controller section)
  SimulationConfig simulation;      ///< for laws that need sample-rate settings (dither)
  double freeze_after_s = 20e-3;    ///< a sample gap longer than this freezes the loop
  PredictionMode prediction_mode = PredictionMode::kRamp;
};

class ControllerCore {
 public:
  explicit ControllerCore(ControllerSettings settings);
  ~ControllerCore();

  /// Returns an error message if the device does not fit the controller's law (the controller
  /// keeps its previous device, if any).
  std::string OnDevice(const DeviceDescription& description);
  /// Returns an error message if the law does not fit the target (the previous one is kept).
  std::string OnTarget(const BenchTarget& target);
  /// A description or target the edge could not read (bus::ReadDevice / ReadTarget): the
  /// status says why the controller waits.
  void OnUnusableDevice(const std::string& reason);
  void OnUnusableTarget(const std::string& reason);
  /// A driver's state (read for control_count() controls).
  void OnState(const DriverState& state);
  /// A polarimeter sample at wall time `wall_ns`, monotonic `now_ns`: the command answering it,
  /// or none (not configured, stale sample). A failed update answers with φ unchanged. The
  /// command is the core's own (valid until the next OnSample call), or nullptr.
  const ControllerCommand* OnSample(const BenchSample& sample, int64_t now_ns, int64_t wall_ns);
  /// A sample or state the edge refused (`reason`: bus::ReadSample / ReadState): counted and
  /// reported in the status.
  void RejectInput(std::string reason);

  /// The status since the previous call (resets the per-interval figures).
  ControllerStatusReport TakeStatus(int64_t now_ns, int64_t wall_ns, uint64_t missed_deadlines);

  /// The device's controls (0 before its description).
  int control_count() const { return chain_ ? chain_->control_count() : 0; }

  bool configured() const { return controller_ != nullptr && have_state_; }
  bool obeyed() const { return obeyed_; }
  const ControlVector& phi() const { return controller_->phi(); }
  /// Malformed samples and driver states (counted together, reported in the status).
  uint64_t rejected_samples() const { return rejected_samples_; }
  const std::string& last_rejection() const { return last_rejection_; }
  const std::string& condition() const { return condition_; }
  /// Delay compensation: on, and the horizon (seconds) the latest update predicted across.
  bool predicting() const { return controller_ != nullptr && controller_->compensator() != nullptr; }
  double prediction_horizon_s() const { return horizon_s_; }
  /// Ramp mode: the rate of the latest command (zero: none).
  const ControlVector& phi_rate_per_s() const { return controller_->rate_per_s(); }

 private:
  /// Builds the controller once the device and the target are known, from the applied φ.
  void BuildController();
  void Resync(const ControlVector& phi);
  /// Real-time. The horizon for the sample at t_ns: the measured loop latency (see the file
  /// comment), or the configured one.
  double PredictionHorizonS(const BenchSample& sample);

  ControllerSettings settings_;
  std::unique_ptr<WaveplateChain> chain_;
  std::unique_ptr<Target> target_;
  std::unique_ptr<PolarizationController> controller_;
  std::string law_name_;

  bool have_state_ = false;
  bool obeyed_ = false;
  bool lockstep_ = false;            ///< the latest sample came from a lockstep bench
  ControlVector applied_phi_;         ///< the applied motion at the latest sample's time
  WaveplateMotion applied_motion_;    ///< from the latest driver state
  uint64_t last_answered_sample_ = 0;  ///< of this controller's latest command
  std::optional<ControllerCommand> last_command_;
  uint64_t last_sample_ = 0;
  int64_t last_sample_ns_ = 0;
  uint64_t sequence_ = 0;
  uint64_t target_revision_ = 0;

  // Delay compensation.
  bool ramp_ = false;                     ///< the latest update was in ramp mode
  int64_t rate_time_ns_ = 0;              ///< the latest rate command's sample time
  double device_max_ramp_s_ = 0.0;        ///< the driver's (device description); 0: no ramps
  int64_t last_sample_time_ns_ = 0;       ///< the latest sample's bench time
  double horizon_s_ = 0.0;                ///< the latest horizon used
  double latency_estimate_s_ = -1.0;      ///< smoothed t_j − t_a; < 0: none yet
  uint64_t state_answers_sample_ = 0;     ///< of the latest state obeying this controller
  static constexpr size_t kSampleTimeRing = 4096;  ///< recent samples' times, by sequence number
  std::array<std::pair<uint64_t, int64_t>, kSampleTimeRing> sample_times_ns_{};
  // Status.
  std::string condition_ = "waiting for the device description";
  double error_deg_ = NAN;
  double sigma_max_ = NAN, sigma_min_ = NAN;
  uint64_t updates_ = 0, failed_updates_ = 0, rejected_samples_ = 0;
  uint64_t interval_updates_ = 0, interval_nullspace_ = 0;
  double interval_compute_s_ = 0.0, interval_compute_max_s_ = 0.0;
  std::string last_rejection_;
};

}  // namespace dpc::services
