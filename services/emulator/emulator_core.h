#pragma once
// dpc-emulator's core: the instruments a lab attaches to the bench, emulated on the TRUE device
// of a scenario — an electronic polarization controller (EPC: one voltage per channel, set over
// text lines) and a polarimeter (S_in and S_out queried over text lines) — and the text
// protocol they speak, handled on byte streams. No sockets and no clock of its own: the
// program (main.cc) feeds it each client's bytes with the monotonic time and writes back what
// it returns; the tests do the same with strings.
//
// The optics (EmulatedDevice). Channel c of the EPC drives control c of the scenario's chain,
// φ = volts:
//
//   V_set    the DAC's code nearest the request: V_min + round((V − V_min)/q)·q,
//            q = (V_max − V_min)/(2^bits − 1); a request outside [V_min, V_max] (or outside the
//            channel's range in the scenario, which narrows it) is refused
//   V_play   the play (backlash) operator of half-width h on V_set: it moves only when V_set
//            pulls it further than h, V_play ← clamp(V_play, V_set − h, V_set + h)
//   V_eff    first-order settling towards V_play, time constant τ (exact over any step: the
//            gap shrinks by exp(−dt/τ); τ = 0: at once)
//   θ_c      θ_c(V_eff)·(1 + k·(T − 25 °C)): the scenario's maps are the truth at 25 °C; the
//            drift scales every retardance (an adjustable-axis stage's orientation is an angle
//            of its axis, not a retardance, and does not drift)
//   S_out    M_m(θ_m)⋯M_1(θ_1) S_in
//
// S_in is the scenario's input: its disturbances step at simulation.sample_rate_hz, one step
// per sample period of the wall clock elapsed (as the real-time polarimeter's input at its
// rate). A measurement adds the scenario's polarimeter noise (PolarimeterNoise; S_in and S_out
// from independent streams, 2 and 3 as in dpc sim). The EPC powers up with every channel at 0 V.
//
// The protocol (EmulatorCore). Lines end with "\n" ("\r\n" accepted), replies with "\n";
// keywords are case-insensitive, blank lines are ignored (no reply).
//
//   EPC          *IDN?              → dpc-emulator,EPC,<channels>,0.1
//                :SOUR<n>:VOLT <v>  → OK (quantized and applied) | ERR <reason>, nothing changes
//                :SOUR<n>:VOLT?     → the set (quantized) voltage, %.6f
//   polarimeter  *IDN?              → dpc-emulator,POL,0,0.1
//                :MEAS:SOP?         → s1,s2,s3 of S_out (%.6f each), measured when the query came
//                :MEAS:SIN?         → S_in likewise;  :MEAS:BOTH? → in1,in2,in3,out1,out2,out3
//                :MEAS:STREAM <SOP|SIN|BOTH> <hz>  → no reply; from then on the session gets the
//                                     reading of that query every 1/hz s (1 Hz to 100 kHz), by
//                                     itself; :MEAS:STREAM OFF stops it. Queries still answer.
//   either       anything else      → ERR unknown command
//   control      see ControlHelp(): faults, power cycle, temperature, wavelength, status (one JSON line)
//
// Every reply of the EPC and the polarimeter leaves latency_s after its query (plus a `slow`
// fault's delay), and the replies of one session in the order of their queries. Faults
// (control port) count the replies of an instrument, whichever session they go to: `garbage`
// replaces a reply by printable punctuation that parses as no reply (and takes precedence),
// `truncate` sends its first half without the newline, `slow` delays it; `disconnect` ends the
// instrument's sessions and refuses new ones for a while, `powercycle` (EPC) does too and
// forgets every voltage.
//
// Bounds, so that nothing a client sends can crash or stall the emulator: a line of more than
// kMaxLineBytes bytes (before its "\r\n") is answered "ERR line too long" and dropped up to its
// newline; a session with more than kMaxQueuedBytes of replies waiting (a client that does not
// read) is ended; at most kMaxSessionsPerInstrument sessions per instrument. Work per byte
// received is bounded, and the input catches up at most kMaxInputCatchUpS of the wall clock per
// Advance (a longer stall of the process is skipped, and counted).

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "dpc/config/scenario_config.h"
#include "dpc/disturbance/input_sop_generator.h"
#include "dpc/disturbance/polarimeter_noise.h"
#include "dpc/disturbance/random_source.h"
#include "dpc/optics/waveplate_chain.h"

namespace dpc::services {

/// The emulated instruments' settings (dpc-emulator's options of the same names). The
/// polarimeter noise and the seed are the scenario's (simulation.polarimeter_noise_deg,
/// simulation.seed: --noise-deg, --seed).
struct EmulatorSettings {
  int dac_bits = 16;
  double volts_min = -10.0;
  double volts_max = 10.0;
  double settling_s = 0.0;                       ///< time constant τ of each channel's settling
  double hysteresis_v = 0.0;                     ///< half-width h of the play operator
  double temperature_c = 25.0;
  double temperature_coefficient_per_k = 2e-3;   ///< k: θ_T = θ·(1 + k·(T − 25 °C))
  double wavelength_nm = 1550.0;                 ///< λ: θ_λ = θ·1550 nm/λ (a retardance goes as 1/λ)
  double latency_s = 0.0;                        ///< each reply leaves this long after its query
};

/// Limits of the settings and the control port's arguments.
inline constexpr int kMaxDacBits = 32;
inline constexpr double kMaxAbsVolts = 1000.0;
inline constexpr double kMaxSettlingS = 3600.0;
inline constexpr double kMaxLatencyS = 60.0;
inline constexpr double kMinTemperatureC = -100.0;
inline constexpr double kMaxTemperatureC = 200.0;
inline constexpr double kMaxTemperatureCoefficientPerK = 0.1;
inline constexpr double kReferenceTemperatureC = 25.0;
/// The scenario's maps are the truth at this wavelength; the light's wavelength is within the
/// span below.
inline constexpr double kReferenceWavelengthNm = 1550.0;
inline constexpr double kMinWavelengthNm = 400.0;
inline constexpr double kMaxWavelengthNm = 2500.0;
/// The input steps in real time, one per sample period: a faster rate would cost more than the
/// emulator may spend (the paper's 50-MHz scenarios are for dpc sim).
inline constexpr double kMaxInputRateHz = 1e6;
/// The longest wall-clock stretch one Advance catches the input up by.
inline constexpr double kMaxInputCatchUpS = 1.0;

/// Throws std::invalid_argument naming the option ("--dac-bits: …") at the first setting out of
/// its range: dac_bits 1…kMaxDacBits; volts_min < volts_max, both within ±kMaxAbsVolts;
/// settling_s ∈ [0, kMaxSettlingS]; hysteresis_v ∈ [0, (volts_max − volts_min)/2];
/// latency_s ∈ [0, kMaxLatencyS]; |temperature_coefficient_per_k| ≤ kMaxTemperatureCoefficientPerK;
/// temperature_c as TemperatureProblem; wavelength_nm as WavelengthProblem.
void ValidateEmulatorSettings(const EmulatorSettings& settings);

/// "" if the device may be at `temperature_c` with coefficient `k`: within [kMinTemperatureC,
/// kMaxTemperatureC] and 1 + k·(T − 25) > 0 (a retardance that vanished or changed sign is no
/// drift); else why not.
std::string TemperatureProblem(double temperature_c, double coefficient_per_k);

/// "" if the light may be at `wavelength_nm`: within [kMinWavelengthNm, kMaxWavelengthNm]; else
/// why not.
std::string WavelengthProblem(double wavelength_nm);

/// The stages with every retardance scaled by `factor` (maps' angles and fixed retardances;
/// orientations unchanged). `factor` > 0.
std::vector<StageConfig> ScaleRetardances(std::vector<StageConfig> stages, double factor);

/// The EPC's DAC: 2^bits codes spread evenly over [volts_min, volts_max], both ends included.
class DacScale {
 public:
  DacScale(int bits, double volts_min, double volts_max);
  /// The code's voltage nearest `volts`, which must lie in [volts_min, volts_max].
  double Quantize(double volts) const;
  double step_v() const { return step_v_; }
  double volts_min() const { return volts_min_; }
  double volts_max() const { return volts_max_; }

 private:
  double volts_min_, volts_max_, step_v_, max_code_;
};

/// One channel's voltage: set (a DAC code) → play operator → first-order settling → effective.
class EpcChannel {
 public:
  EpcChannel(double hysteresis_v, double settling_s) : hysteresis_v_(hysteresis_v), settling_s_(settling_s) {}
  /// A new set voltage (already quantized). Moves the play operator's output at once.
  void Set(double volts);
  /// Settles the effective voltage over `dt_s` ≥ 0.
  void Advance(double dt_s);
  /// Everything at 0 V (a power cycle).
  void Reset();
  double set_v() const { return set_v_; }
  double play_v() const { return play_v_; }
  double effective_v() const { return effective_v_; }

 private:
  double hysteresis_v_, settling_s_;
  double set_v_ = 0.0, play_v_ = 0.0, effective_v_ = 0.0;
};

/// The simulated optics behind both instruments (see the file comment).
class EmulatedDevice {
 public:
  /// `scenario` is validated whole (ValidateScenario; ScenarioError) and its sample rate must be
  /// at most kMaxInputRateHz (ScenarioError at simulation.sample_rate_hz); `settings` valid
  /// (ValidateEmulatorSettings: std::invalid_argument). `now_ns`: monotonic, the input's start.
  EmulatedDevice(const ScenarioConfig& scenario, const EmulatorSettings& settings, int64_t now_ns);

  /// The input and the channels' settling to `now_ns` (an earlier time changes nothing).
  void Advance(int64_t now_ns);

  int channel_count() const { return static_cast<int>(channels_.size()); }
  /// "" and the channel (0-based) set to the quantized voltage, or why not (nothing changes).
  std::string SetVoltage(int channel, double volts);
  double set_v(int channel) const { return channels_[channel].set_v(); }
  double effective_v(int channel) const { return channels_[channel].effective_v(); }
  const DacScale& dac() const { return dac_; }

  /// Every channel at 0 V, effective too.
  void PowerCycle();

  /// "" and the temperature set, or why not (TemperatureProblem; nothing changes).
  std::string SetTemperature(double temperature_c);
  double temperature_c() const { return temperature_c_; }
  /// "" and the light's wavelength set, or why not (WavelengthProblem; nothing changes).
  std::string SetWavelength(double wavelength_nm);
  double wavelength_nm() const { return wavelength_nm_; }

  /// The true SOPs now (after Advance), no noise.
  const StokesVector& s_in() const { return input_.current_sop(); }
  StokesVector s_out() const;
  /// A polarimeter's readings: the true SOP with the configured noise.
  StokesVector MeasureInput() { return input_noise_.Measure(s_in()); }
  StokesVector MeasureOutput() { return output_noise_.Measure(s_out()); }

  /// Input steps taken, and skipped after stalls of the process longer than kMaxInputCatchUpS.
  int64_t input_steps() const { return input_.sample_index(); }
  int64_t input_steps_skipped() const { return input_steps_skipped_; }
  const WaveplateChain& chain() const { return *chain_; }

 private:
  void BuildChainAt(double temperature_c, double wavelength_nm);

  std::vector<StageConfig> stages_;  ///< the truth at 25 °C and 1550 nm
  EmulatorSettings settings_;
  DacScale dac_;
  std::unique_ptr<WaveplateChain> chain_;  ///< at temperature_c_ and wavelength_nm_
  double temperature_c_;
  double wavelength_nm_;
  std::vector<EpcChannel> channels_;
  InputSopGenerator input_;
  double input_rate_hz_;
  int64_t start_ns_;
  int64_t last_ns_;
  int64_t input_steps_skipped_ = 0;  ///< the input's clock lags the wall clock by these
  PolarimeterNoise input_noise_;
  PolarimeterNoise output_noise_;
  mutable ControlVector volts_;       ///< scratch for s_out()
};

enum class Instrument { kEpc, kPolarimeter, kControl };
/// "epc", "polarimeter", "control".
const char* InstrumentName(Instrument instrument);

/// The control port's commands, one line each (the reply to `help`).
std::string ControlHelp();

/// The instruments' protocol on byte streams: sessions (a TCP connection, a pseudo-terminal's
/// reader, a test's string), their line buffers and reply queues, the faults and the counters.
class EmulatorCore {
 public:
  static constexpr size_t kMaxLineBytes = 256;
  static constexpr size_t kMaxQueuedBytes = 64 * 1024;
  static constexpr int kMaxSessionsPerInstrument = 128;
  /// Faults' counts and durations the control port accepts.
  static constexpr int64_t kMaxFaultCount = 1'000'000'000;
  static constexpr double kMaxFaultS = 3600.0;
  static constexpr double kDefaultPowerCycleS = 0.5;
  /// A stream's rate, and the most lines one Output call produces for a stream that fell behind
  /// (the older ones are skipped: a stalled program never floods its client afterwards).
  static constexpr double kMinStreamHz = 1.0, kMaxStreamHz = 100'000.0;
  static constexpr int kMaxStreamLinesPerOutput = 16;

  using SessionId = uint64_t;
  /// Something worth a line in the program's log: a control command obeyed, a session ended by
  /// the emulator. `kind` groups lines for rate limiting ("control", "dropped").
  using EventSink = std::function<void(const std::string& kind, const std::string& text)>;

  /// As EmulatedDevice's constructor (ScenarioError, std::invalid_argument).
  EmulatorCore(const ScenarioConfig& scenario, const EmulatorSettings& settings, int64_t now_ns,
               EventSink on_event = nullptr);

  /// A new client of `instrument`; nullopt when refused (the instrument is unreachable after a
  /// `disconnect` or `powercycle`, or has kMaxSessionsPerInstrument sessions).
  std::optional<SessionId> Open(Instrument instrument, int64_t now_ns);
  /// Whether a new client of `instrument` would be taken now (a pseudo-terminal waits for it).
  bool Reachable(Instrument instrument, int64_t now_ns) const;
  /// The client went away (or the program gave up on it). Unknown ids are ignored.
  void Close(SessionId id);
  /// Bytes from the client (any amount, any content). Unknown or ended sessions: ignored.
  void Receive(SessionId id, std::string_view bytes, int64_t now_ns);
  /// The bytes due to the client by `now_ns`, to write; then Written with how many were.
  std::string_view Output(SessionId id, int64_t now_ns);
  void Written(SessionId id, size_t bytes);
  /// Sessions the emulator ended since the last call (disconnect, power cycle, a client that
  /// does not read): the program closes their connections. Each also counts as Closed.
  std::vector<SessionId> TakeEnded();
  /// Whether the session exists and has not been ended.
  bool IsOpen(SessionId id) const { return sessions_.count(id) != 0; }
  /// The instrument of an open session.
  std::optional<Instrument> InstrumentOf(SessionId id) const;

  /// The optics to `now_ns` (the program calls it at least every millisecond).
  void Advance(int64_t now_ns) { device_.Advance(now_ns); }
  /// The earliest time a queued reply falls due (INT64_MAX: none).
  int64_t NextDueNs() const;

  /// The `status` reply: channels, temperature, S_in, S_out, counters, active faults.
  nlohmann::ordered_json Status(int64_t now_ns) const;

  EmulatedDevice& device() { return device_; }
  const EmulatedDevice& device() const { return device_; }

 private:
  struct PendingReply {
    int64_t due_ns;
    std::string bytes;
  };
  struct Session {
    Instrument instrument;
    std::string line;            ///< the line being received (≤ kMaxLineBytes + 1 bytes)
    bool discarding = false;     ///< dropping the rest of a line that was too long
    std::deque<PendingReply> pending;
    size_t pending_bytes = 0;
    int64_t last_due_ns = 0;     ///< replies leave in order
    std::string out;             ///< due, not yet written
    std::string stream_query;    ///< the polarimeter's query a stream answers ("": no stream)
    int64_t stream_period_ns = 0;
    int64_t next_stream_ns = 0;
  };
  /// Every line handled is one query, set or error (the control port: commands and errors).
  struct Counters {
    uint64_t queries = 0, sets = 0, errors = 0;
    uint64_t accepted = 0, refused = 0, ended = 0;
    uint64_t streamed = 0, stream_skipped = 0;
  };
  struct Faults {
    int64_t garbage = 0, truncate = 0, slow = 0;
    double slow_s = 0.0;
    int64_t unreachable_until_ns = 0;
    std::string unreachable_reason;
  };

  void HandleLine(SessionId id, Session& session, std::string_view line, int64_t now_ns);
  std::string EpcReply(std::string_view line, Counters& counters);
  std::string PolarimeterReply(std::string_view line, Counters& counters);
  /// `:MEAS:STREAM …` on `session`: "" when taken (no reply), else the error to send.
  std::string StartStream(Session& session, std::string_view line, int64_t now_ns);
  /// The stream's lines due by `now_ns`, queued as replies.
  void PumpStream(SessionId id, Session& session, int64_t now_ns);
  std::string ControlReply(SessionId id, std::string_view line, int64_t now_ns);
  /// Queues `reply` (no newline) on the session, with the instrument's faults and latency;
  /// false if the session was ended for it (too much queued).
  bool Reply(SessionId id, Session& session, std::string reply, int64_t now_ns);
  void End(SessionId id, const std::string& why);
  /// Ends every session of `instrument` but `except`; how many.
  int EndAll(Instrument instrument, const std::string& why, SessionId except);
  std::string Garbage();
  Counters& CountersOf(Instrument instrument) { return counters_[static_cast<int>(instrument)]; }
  void Event(const std::string& kind, const std::string& text) const {
    if (on_event_) on_event_(kind, text);
  }

  EmulatedDevice device_;
  int64_t start_ns_;
  int64_t latency_ns_;
  EventSink on_event_;
  std::map<SessionId, Session> sessions_;
  SessionId next_id_ = 1;
  std::vector<SessionId> ended_;
  std::array<Counters, 3> counters_{};  ///< by Instrument
  std::array<Faults, 2> faults_{};      ///< EPC, polarimeter
  RandomSource garbage_random_;
};

}  // namespace dpc::services
