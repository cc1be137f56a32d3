#include "emulator_core.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <system_error>

#include <fmt/format.h>

#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_error.h"
#include "dpc/config/scenario_validation.h"
#include "dpc/disturbance/random_source.h"

namespace dpc::services {
namespace {

/// Random streams of the seed (RandomSource): the input uses 1; the polarimeters 2 (S_in) and 3
/// (S_out), as in dpc sim; the garbage replies 4.
constexpr uint64_t kInputPolarimeterStream = 2;
constexpr uint64_t kOutputPolarimeterStream = 3;
constexpr uint64_t kGarbageStream = 4;

/// Printable junk that parses as no reply: no letter, digit, sign, point or comma.
constexpr std::string_view kGarbageAlphabet = "!#$%&*/:;<=>?@[]^_{|}~";

int64_t SecondsToNs(double seconds) { return static_cast<int64_t>(std::llround(seconds * 1e9)); }

void RequireInRange(double value, double min, double max, const char* option, const char* what) {
  if (!(std::isfinite(value) && value >= min && value <= max)) {
    throw std::invalid_argument(fmt::format("{}: {} is not in [{}, {}] ({})", option, value, min, max, what));
  }
}

std::string_view Trim(std::string_view text) {
  const auto blank = [](char c) { return c == ' ' || c == '\t'; };
  while (!text.empty() && blank(text.front())) text.remove_prefix(1);
  while (!text.empty() && blank(text.back())) text.remove_suffix(1);
  return text;
}

std::string Lower(std::string_view text) {
  std::string lower(text);
  for (char& c : lower) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return lower;
}

std::vector<std::string_view> Words(std::string_view text) {
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    const size_t begin = i;
    while (i < text.size() && text[i] != ' ' && text[i] != '\t') ++i;
    if (i > begin) words.push_back(text.substr(begin, i - begin));
  }
  return words;
}

enum class NumberParse { kOk, kNotANumber, kNotFinite };

/// A decimal number ("5", "-2.5", "+1e-3"); "inf", "nan" and numbers beyond a double's range
/// are not finite.
NumberParse ParseNumber(std::string_view text, double* value) {
  if (text.size() > 1 && text[0] == '+' && text[1] != '-' && text[1] != '+') text.remove_prefix(1);
  if (text.empty()) return NumberParse::kNotANumber;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), *value, std::chars_format::general);
  if (end != text.data() + text.size()) return NumberParse::kNotANumber;
  if (error == std::errc::result_out_of_range) return NumberParse::kNotFinite;
  if (error != std::errc()) return NumberParse::kNotANumber;
  return std::isfinite(*value) ? NumberParse::kOk : NumberParse::kNotFinite;
}

/// A whole number in [0, max], or nullopt.
std::optional<int64_t> ParseCount(std::string_view text, int64_t max) {
  int64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || value < 0 || value > max) return std::nullopt;
  return value;
}

/// Seconds in [0, max], or nullopt.
std::optional<double> ParseSeconds(std::string_view text, double max) {
  double value = 0.0;
  if (ParseNumber(text, &value) != NumberParse::kOk || value < 0.0 || value > max) return std::nullopt;
  return value;
}

std::string FormatSop(const StokesVector& s) { return fmt::format("{:.6f},{:.6f},{:.6f}", s.x(), s.y(), s.z()); }

void ScaleMap(ControlMapConfig* map, double factor) {
  map->rad_per_unit *= factor;
  map->offset_rad *= factor;
  for (double& c : map->coefficients_rad) c *= factor;
  for (double& a : map->table_angle_rad) a *= factor;
  for (ConditionTableConfig& table : map->condition_tables) {
    for (double& a : table.angle_rad) a *= factor;
  }
}

nlohmann::ordered_json Vector(const StokesVector& s) { return {s.x(), s.y(), s.z()}; }

}  // namespace

// ---- settings -------------------------------------------------------------------------------

std::string TemperatureProblem(double temperature_c, double coefficient_per_k) {
  if (!(std::isfinite(temperature_c) && temperature_c >= kMinTemperatureC && temperature_c <= kMaxTemperatureC)) {
    return fmt::format("{} °C is not in [{}, {}] °C", temperature_c, kMinTemperatureC, kMaxTemperatureC);
  }
  const double factor = 1.0 + coefficient_per_k * (temperature_c - kReferenceTemperatureC);
  if (!(factor > 0.0)) {
    return fmt::format("at {} °C the retardance factor 1 + {}·(T − 25) would be {:.4g}: not a drift the emulator "
                       "models (it must stay > 0)",
                       temperature_c, coefficient_per_k, factor);
  }
  return {};
}

std::string WavelengthProblem(double wavelength_nm) {
  if (!(std::isfinite(wavelength_nm) && wavelength_nm >= kMinWavelengthNm && wavelength_nm <= kMaxWavelengthNm)) {
    return fmt::format("{} nm is not in [{}, {}] nm", wavelength_nm, kMinWavelengthNm, kMaxWavelengthNm);
  }
  return {};
}

void ValidateEmulatorSettings(const EmulatorSettings& s) {
  if (s.dac_bits < 1 || s.dac_bits > kMaxDacBits) {
    throw std::invalid_argument(fmt::format("--dac-bits: {} is not in [1, {}]", s.dac_bits, kMaxDacBits));
  }
  RequireInRange(s.volts_min, -kMaxAbsVolts, kMaxAbsVolts, "--volts-min", "the DAC's full scale, volts");
  RequireInRange(s.volts_max, -kMaxAbsVolts, kMaxAbsVolts, "--volts-max", "the DAC's full scale, volts");
  if (!(s.volts_min < s.volts_max)) {
    throw std::invalid_argument(
        fmt::format("--volts-max: {} is not above --volts-min {} (the DAC's full scale)", s.volts_max, s.volts_min));
  }
  RequireInRange(s.settling_s, 0.0, kMaxSettlingS, "--settling-s", "the channels' settling time constant");
  RequireInRange(s.hysteresis_v, 0.0, 0.5 * (s.volts_max - s.volts_min), "--hysteresis-v",
                 "the play operator's half-width, at most half the full scale");
  RequireInRange(s.latency_s, 0.0, kMaxLatencyS, "--latency-s", "the delay of every reply");
  RequireInRange(s.temperature_coefficient_per_k, -kMaxTemperatureCoefficientPerK, kMaxTemperatureCoefficientPerK,
                 "--temperature-coefficient-per-k", "the retardance's relative change per kelvin");
  if (const std::string problem = TemperatureProblem(s.temperature_c, s.temperature_coefficient_per_k);
      !problem.empty()) {
    throw std::invalid_argument("--temperature-c: " + problem);
  }
  if (const std::string problem = WavelengthProblem(s.wavelength_nm); !problem.empty()) {
    throw std::invalid_argument("--wavelength-nm: " + problem);
  }
}

std::vector<StageConfig> ScaleRetardances(std::vector<StageConfig> stages, double factor) {
  for (StageConfig& stage : stages) {
    if (stage.kind == StageConfig::Kind::kFixedAxis) {
      ScaleMap(&stage.map, factor);
    } else if (stage.retardance.controlled) {
      ScaleMap(&stage.retardance.map, factor);
    } else {
      stage.retardance.fixed_rad *= factor;
    }
  }
  return stages;
}

// ---- the DAC and the channels ----------------------------------------------------------------

DacScale::DacScale(int bits, double volts_min, double volts_max)
    : volts_min_(volts_min),
      volts_max_(volts_max),
      step_v_((volts_max - volts_min) / (std::ldexp(1.0, bits) - 1.0)),
      max_code_(std::ldexp(1.0, bits) - 1.0) {}

double DacScale::Quantize(double volts) const {
  const double code = std::clamp(std::round((volts - volts_min_) / step_v_), 0.0, max_code_);
  // The top code is the full scale's end exactly (no round-off above it).
  return code == max_code_ ? volts_max_ : volts_min_ + code * step_v_;
}

void EpcChannel::Set(double volts) {
  set_v_ = volts;
  play_v_ = std::clamp(play_v_, set_v_ - hysteresis_v_, set_v_ + hysteresis_v_);
  if (settling_s_ == 0.0) effective_v_ = play_v_;
}

void EpcChannel::Advance(double dt_s) {
  if (settling_s_ == 0.0) {
    effective_v_ = play_v_;
    return;
  }
  if (dt_s <= 0.0) return;
  effective_v_ = play_v_ + (effective_v_ - play_v_) * std::exp(-dt_s / settling_s_);
}

void EpcChannel::Reset() { set_v_ = play_v_ = effective_v_ = 0.0; }

// ---- the device ------------------------------------------------------------------------------

namespace {

/// The scenario as the emulator runs it: valid for dpc sim, and an input it can step in real time.
const ScenarioConfig& Checked(const ScenarioConfig& scenario) {
  ValidateScenario(scenario);
  if (scenario.simulation.sample_rate_hz > kMaxInputRateHz) {
    throw ScenarioError("simulation.sample_rate_hz",
                        fmt::format("{:g} Hz is above the {:g} Hz the emulator steps its input at in real time "
                                    "(the input's disturbances advance one step per sample period of the wall clock)",
                                    scenario.simulation.sample_rate_hz, kMaxInputRateHz));
  }
  return scenario;
}

const EmulatorSettings& Checked(const EmulatorSettings& settings) {
  ValidateEmulatorSettings(settings);
  return settings;
}

}  // namespace

EmulatedDevice::EmulatedDevice(const ScenarioConfig& scenario, const EmulatorSettings& settings, int64_t now_ns)
    : stages_(Checked(scenario).stages),
      settings_(Checked(settings)),
      dac_(settings.dac_bits, settings.volts_min, settings.volts_max),
      temperature_c_(settings.temperature_c),
      wavelength_nm_(settings.wavelength_nm),
      input_(MakeInputSopGenerator(scenario.input, scenario.simulation.seed, scenario.simulation.sample_rate_hz)),
      input_rate_hz_(scenario.simulation.sample_rate_hz),
      start_ns_(now_ns),
      last_ns_(now_ns),
      input_noise_(scenario.simulation.polarimeter_noise_deg, scenario.simulation.seed, kInputPolarimeterStream),
      output_noise_(scenario.simulation.polarimeter_noise_deg, scenario.simulation.seed, kOutputPolarimeterStream) {
  BuildChainAt(temperature_c_, wavelength_nm_);
  channels_.assign(chain_->control_count(), EpcChannel(settings.hysteresis_v, settings.settling_s));
  volts_ = ControlVector::Zero(chain_->control_count());
  input_.Next();  // S_in[0]: the initial SOP
}

void EmulatedDevice::BuildChainAt(double temperature_c, double wavelength_nm) {
  const double factor = (1.0 + settings_.temperature_coefficient_per_k * (temperature_c - kReferenceTemperatureC)) *
                        (kReferenceWavelengthNm / wavelength_nm);
  chain_ = std::make_unique<WaveplateChain>(BuildChain(factor == 1.0 ? stages_ : ScaleRetardances(stages_, factor)));
}

void EmulatedDevice::Advance(int64_t now_ns) {
  if (now_ns <= last_ns_) return;
  const double dt_s = static_cast<double>(now_ns - last_ns_) * 1e-9;
  last_ns_ = now_ns;
  for (EpcChannel& channel : channels_) channel.Advance(dt_s);
  // Step k of the input belongs to the wall clock's k-th sample period since the start, less
  // the steps skipped after stalls.
  const double elapsed_s = static_cast<double>(now_ns - start_ns_) * 1e-9;
  int64_t due = static_cast<int64_t>(std::floor(elapsed_s * input_rate_hz_)) - input_steps_skipped_;
  const int64_t most = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(kMaxInputCatchUpS * input_rate_hz_)));
  if (due - input_.sample_index() > most) {
    input_steps_skipped_ += due - input_.sample_index() - most;
    due = input_.sample_index() + most;
  }
  while (input_.sample_index() < due) input_.Next();
}

std::string EmulatedDevice::SetVoltage(int channel, double volts) {
  if (channel < 0 || channel >= channel_count()) {
    return fmt::format("unknown channel {} (channels 1-{})", channel + 1, channel_count());
  }
  if (!std::isfinite(volts)) return "voltage not finite";
  if (volts < dac_.volts_min() || volts > dac_.volts_max()) {
    return fmt::format("{:g} V is outside the full scale [{:g}, {:g}] V", volts, dac_.volts_min(), dac_.volts_max());
  }
  if (const std::optional<ControlRange>& range = chain_->controls()[channel].range;
      range && !range->Contains(volts)) {
    return fmt::format("{:g} V is outside channel {}'s range [{:g}, {:g}] V", volts, channel + 1, range->min,
                       range->max);
  }
  channels_[channel].Set(dac_.Quantize(volts));
  return {};
}

void EmulatedDevice::PowerCycle() {
  for (EpcChannel& channel : channels_) channel.Reset();
}

std::string EmulatedDevice::SetTemperature(double temperature_c) {
  if (std::string problem = TemperatureProblem(temperature_c, settings_.temperature_coefficient_per_k);
      !problem.empty()) {
    return problem;
  }
  BuildChainAt(temperature_c, wavelength_nm_);
  temperature_c_ = temperature_c;
  return {};
}

std::string EmulatedDevice::SetWavelength(double wavelength_nm) {
  if (std::string problem = WavelengthProblem(wavelength_nm); !problem.empty()) return problem;
  BuildChainAt(temperature_c_, wavelength_nm);
  wavelength_nm_ = wavelength_nm;
  return {};
}

StokesVector EmulatedDevice::s_out() const {
  for (int c = 0; c < channel_count(); ++c) volts_[c] = channels_[c].effective_v();
  return chain_->Output(volts_, s_in());
}

// ---- the protocol ----------------------------------------------------------------------------

const char* InstrumentName(Instrument instrument) {
  switch (instrument) {
    case Instrument::kEpc: return "epc";
    case Instrument::kPolarimeter: return "polarimeter";
    case Instrument::kControl: return "control";
  }
  return "?";
}

std::string ControlHelp() {
  return "disconnect epc|polarimeter|all [seconds]; garbage epc|polarimeter <count>; "
         "truncate epc|polarimeter <count>; slow epc|polarimeter <seconds> <count>; powercycle [seconds]; "
         "temperature <celsius>; wavelength <nm>; status; help";
}

EmulatorCore::EmulatorCore(const ScenarioConfig& scenario, const EmulatorSettings& settings, int64_t now_ns,
                           EventSink on_event)
    : device_(scenario, settings, now_ns),
      start_ns_(now_ns),
      latency_ns_(SecondsToNs(settings.latency_s)),
      on_event_(std::move(on_event)),
      garbage_random_(scenario.simulation.seed, kGarbageStream) {}

bool EmulatorCore::Reachable(Instrument instrument, int64_t now_ns) const {
  return instrument == Instrument::kControl || now_ns >= faults_[static_cast<int>(instrument)].unreachable_until_ns;
}

std::optional<EmulatorCore::SessionId> EmulatorCore::Open(Instrument instrument, int64_t now_ns) {
  Counters& counters = CountersOf(instrument);
  const auto open = std::count_if(sessions_.begin(), sessions_.end(),
                                  [&](const auto& entry) { return entry.second.instrument == instrument; });
  if (!Reachable(instrument, now_ns) || open >= kMaxSessionsPerInstrument) {
    ++counters.refused;
    return std::nullopt;
  }
  ++counters.accepted;
  const SessionId id = next_id_++;
  Session& session = sessions_[id];
  session.instrument = instrument;
  return id;
}

std::optional<Instrument> EmulatorCore::InstrumentOf(SessionId id) const {
  const auto it = sessions_.find(id);
  if (it == sessions_.end()) return std::nullopt;
  return it->second.instrument;
}

void EmulatorCore::Close(SessionId id) { sessions_.erase(id); }

void EmulatorCore::End(SessionId id, const std::string& why) {
  const auto it = sessions_.find(id);
  if (it == sessions_.end()) return;
  ++CountersOf(it->second.instrument).ended;
  sessions_.erase(it);
  ended_.push_back(id);
  if (!why.empty()) Event("ended", why);
}

int EmulatorCore::EndAll(Instrument instrument, const std::string& why, SessionId except) {
  std::vector<SessionId> ids;
  for (const auto& [id, session] : sessions_) {
    if (session.instrument == instrument && id != except) ids.push_back(id);
  }
  for (SessionId id : ids) End(id, "");
  if (!ids.empty() && !why.empty()) Event("ended", why);
  return static_cast<int>(ids.size());
}

std::vector<EmulatorCore::SessionId> EmulatorCore::TakeEnded() {
  std::vector<SessionId> ended;
  ended.swap(ended_);
  return ended;
}

void EmulatorCore::Receive(SessionId id, std::string_view bytes, int64_t now_ns) {
  if (!IsOpen(id)) return;
  device_.Advance(now_ns);
  for (const char c : bytes) {
    Session& session = sessions_.find(id)->second;
    if (c == '\n') {
      if (session.discarding) {
        session.discarding = false;
        continue;
      }
      std::string line;
      line.swap(session.line);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.size() > kMaxLineBytes) {
        ++CountersOf(session.instrument).errors;
        Reply(id, session, "ERR line too long", now_ns);
      } else {
        HandleLine(id, session, line, now_ns);
      }
    } else if (session.discarding) {
      continue;
    } else if (session.line.size() > kMaxLineBytes) {
      // kMaxLineBytes + 1 held (room for a '\r' before the newline): this line is too long.
      session.line.clear();
      session.discarding = true;
      ++CountersOf(session.instrument).errors;
      Reply(id, session, "ERR line too long", now_ns);
    } else {
      session.line.push_back(c);
    }
    if (!IsOpen(id)) return;  // ended: it queued more than a client that reads would
  }
}

void EmulatorCore::HandleLine(SessionId id, Session& session, std::string_view line, int64_t now_ns) {
  line = Trim(line);
  if (line.empty()) return;  // a blank line asks nothing (clients send one to clear a partial line)
  std::string reply;
  if (session.instrument == Instrument::kPolarimeter && Lower(line).starts_with(":meas:stream")) {
    reply = StartStream(session, line, now_ns);
    if (reply.empty()) return;  // taken: a stream start is not answered
    Reply(id, session, std::move(reply), now_ns);
    return;
  }
  switch (session.instrument) {
    case Instrument::kEpc: reply = EpcReply(line, CountersOf(Instrument::kEpc)); break;
    case Instrument::kPolarimeter: reply = PolarimeterReply(line, CountersOf(Instrument::kPolarimeter)); break;
    case Instrument::kControl: reply = ControlReply(id, line, now_ns); break;
  }
  Reply(id, session, std::move(reply), now_ns);
}

std::string EmulatorCore::EpcReply(std::string_view line, Counters& counters) {
  const std::string upper = [&] {
    std::string u(line);
    for (char& c : u) {
      if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
    }
    return u;
  }();
  const auto error = [&](std::string reason) {
    ++counters.errors;
    return "ERR " + reason;
  };
  if (upper == "*IDN?") {
    ++counters.queries;
    return fmt::format("dpc-emulator,EPC,{},0.1", device_.channel_count());
  }
  // :SOUR<n>:VOLT <v> | :SOUR<n>:VOLT?
  constexpr std::string_view kSource = ":SOUR", kVolt = ":VOLT";
  if (!upper.starts_with(kSource)) return error("unknown command");
  size_t i = kSource.size();
  const size_t digits = i;
  while (i < upper.size() && upper[i] >= '0' && upper[i] <= '9') ++i;
  const std::string_view number = std::string_view(upper).substr(digits, i - digits);
  if (number.empty() || upper.compare(i, kVolt.size(), kVolt) != 0) return error("unknown command");
  const std::string_view rest = line.substr(i + kVolt.size());
  const bool query = rest == "?";
  if (!query && (rest.empty() || (rest.front() != ' ' && rest.front() != '\t'))) return error("unknown command");
  // 1-based on the wire; more digits than any channel count has is simply no channel.
  const std::optional<int64_t> channel = ParseCount(number, 1'000'000);
  if (!channel || *channel < 1 || *channel > device_.channel_count()) {
    return error(fmt::format("unknown channel{}{} (channels 1-{})", number.size() <= 9 ? " " : "",
                             number.size() <= 9 ? number : "", device_.channel_count()));
  }
  const int c = static_cast<int>(*channel) - 1;
  if (query) {
    ++counters.queries;
    return fmt::format("{:.6f}", device_.set_v(c));
  }
  double volts = 0.0;
  switch (ParseNumber(Trim(rest), &volts)) {
    case NumberParse::kNotANumber: return error("voltage is not a decimal number");
    case NumberParse::kNotFinite: return error("voltage not finite");
    case NumberParse::kOk: break;
  }
  if (std::string problem = device_.SetVoltage(c, volts); !problem.empty()) return error(std::move(problem));
  ++counters.sets;
  return "OK";
}

std::string EmulatorCore::PolarimeterReply(std::string_view line, Counters& counters) {
  const std::string lower = Lower(line);
  ++counters.queries;
  if (lower == "*idn?") return "dpc-emulator,POL,0,0.1";
  if (lower == ":meas:sop?") return FormatSop(device_.MeasureOutput());
  if (lower == ":meas:sin?") return FormatSop(device_.MeasureInput());
  if (lower == ":meas:both?") {
    const StokesVector s_in = device_.MeasureInput();
    return FormatSop(s_in) + "," + FormatSop(device_.MeasureOutput());
  }
  --counters.queries;
  ++counters.errors;
  return "ERR unknown command";
}

std::string EmulatorCore::StartStream(Session& session, std::string_view line, int64_t now_ns) {
  Counters& counters = CountersOf(Instrument::kPolarimeter);
  const std::vector<std::string_view> words = Words(line);
  const auto error = [&](const std::string& reason) {
    ++counters.errors;
    return "ERR " + reason;
  };
  if (Lower(words.front()) != ":meas:stream") return error("unknown command");
  if (words.size() == 2 && Lower(words[1]) == "off") {
    ++counters.queries;
    session.stream_query.clear();
    return {};
  }
  constexpr const char* kUsage = "usage: :MEAS:STREAM SOP|SIN|BOTH <hz> | :MEAS:STREAM OFF";
  if (words.size() != 3) return error(kUsage);
  const std::string what = Lower(words[1]);
  if (what != "sop" && what != "sin" && what != "both") return error(kUsage);
  const std::string rate(words[2]);
  char* end = nullptr;
  const double hz = std::strtod(rate.c_str(), &end);
  if (end == rate.c_str() || *end != '\0' || !(hz >= kMinStreamHz && hz <= kMaxStreamHz)) {
    return error(fmt::format("a stream rate from {} to {} Hz", kMinStreamHz, kMaxStreamHz));
  }
  ++counters.queries;
  session.stream_query = ":meas:" + what + "?";
  session.stream_period_ns = std::max<int64_t>(1, static_cast<int64_t>(std::llround(1e9 / hz)));
  session.next_stream_ns = now_ns + session.stream_period_ns;
  return {};
}

void EmulatorCore::PumpStream(SessionId id, Session& session, int64_t now_ns) {
  if (session.stream_query.empty() || session.next_stream_ns > now_ns) return;
  Counters& counters = CountersOf(Instrument::kPolarimeter);
  const int64_t due = (now_ns - session.next_stream_ns) / session.stream_period_ns + 1;
  const int64_t lines = std::min<int64_t>(due, kMaxStreamLinesPerOutput);
  counters.stream_skipped += static_cast<uint64_t>(due - lines);
  session.next_stream_ns += due * session.stream_period_ns;
  const std::string query = session.stream_query;
  for (int64_t i = 0; i < lines; ++i) {
    Counters ignored;
    ++counters.streamed;
    if (!Reply(id, session, PolarimeterReply(query, ignored), now_ns)) return;  // ended: too much queued
  }
}

std::string EmulatorCore::ControlReply(SessionId id, std::string_view line, int64_t now_ns) {
  Counters& counters = CountersOf(Instrument::kControl);
  const std::vector<std::string_view> words = Words(line);
  const std::string command = Lower(words.front());
  const auto error = [&](const std::string& reason) {
    ++counters.errors;
    return "ERR " + reason;
  };
  const auto usage = [&](const char* text) { return error(fmt::format("usage: {}", text)); };
  // "epc" or "polarimeter" (and "all" where allowed) → the instruments meant.
  const auto instruments = [&](std::string_view word, bool all) -> std::vector<Instrument> {
    const std::string name = Lower(word);
    if (name == "epc") return {Instrument::kEpc};
    if (name == "polarimeter") return {Instrument::kPolarimeter};
    if (all && name == "all") return {Instrument::kEpc, Instrument::kPolarimeter};
    return {};
  };
  const auto ok = [&](std::string text) {
    ++counters.queries;
    Event("control", text);
    return "OK " + text;
  };

  if (command == "status" && words.size() == 1) {
    std::string status = Status(now_ns).dump();  // counts the commands before this one
    ++counters.queries;
    return status;
  }
  if (command == "help" && words.size() == 1) {
    ++counters.queries;
    return "OK " + ControlHelp();
  }
  if (command == "disconnect") {
    const char* kUsage = "disconnect epc|polarimeter|all [seconds]";
    if (words.size() < 2 || words.size() > 3) return usage(kUsage);
    const std::vector<Instrument> which = instruments(words[1], true);
    if (which.empty()) return usage(kUsage);
    std::optional<double> seconds = 0.0;
    if (words.size() == 3) seconds = ParseSeconds(words[2], kMaxFaultS);
    if (!seconds) return error(fmt::format("seconds must be a number in [0, {:g}]", kMaxFaultS));
    int ended = 0;
    for (Instrument instrument : which) {
      ended += EndAll(instrument, "", id);
      Faults& faults = faults_[static_cast<int>(instrument)];
      const int64_t until_ns = now_ns + SecondsToNs(*seconds);
      if (until_ns > faults.unreachable_until_ns) {
        faults.unreachable_until_ns = until_ns;
        faults.unreachable_reason = "disconnect";
      }
    }
    return ok(fmt::format("disconnect {}: {} session{} ended, new ones refused for {:g} s", Lower(words[1]), ended,
                          ended == 1 ? "" : "s", *seconds));
  }
  if (command == "garbage" || command == "truncate") {
    const std::string kUsage = command + " epc|polarimeter <count>";
    if (words.size() != 3) return usage(kUsage.c_str());
    const std::vector<Instrument> which = instruments(words[1], false);
    const std::optional<int64_t> count = ParseCount(words[2], kMaxFaultCount);
    if (which.empty()) return usage(kUsage.c_str());
    if (!count) return error(fmt::format("count must be a whole number in [0, {}]", kMaxFaultCount));
    Faults& faults = faults_[static_cast<int>(which.front())];
    (command == "garbage" ? faults.garbage : faults.truncate) = *count;
    return ok(fmt::format("{} {}: the next {} repl{}", command, InstrumentName(which.front()), *count,
                          *count == 1 ? "y" : "ies"));
  }
  if (command == "slow") {
    const char* kUsage = "slow epc|polarimeter <seconds> <count>";
    if (words.size() != 4) return usage(kUsage);
    const std::vector<Instrument> which = instruments(words[1], false);
    if (which.empty()) return usage(kUsage);
    const std::optional<double> seconds = ParseSeconds(words[2], kMaxFaultS);
    const std::optional<int64_t> count = ParseCount(words[3], kMaxFaultCount);
    if (!seconds) return error(fmt::format("seconds must be a number in [0, {:g}]", kMaxFaultS));
    if (!count) return error(fmt::format("count must be a whole number in [0, {}]", kMaxFaultCount));
    Faults& faults = faults_[static_cast<int>(which.front())];
    faults.slow = *count;
    faults.slow_s = *seconds;
    return ok(fmt::format("slow {}: the next {} repl{} {:g} s late", InstrumentName(which.front()), *count,
                          *count == 1 ? "y" : "ies", *seconds));
  }
  if (command == "powercycle") {
    if (words.size() > 2) return usage("powercycle [seconds]");
    std::optional<double> seconds = kDefaultPowerCycleS;
    if (words.size() == 2) seconds = ParseSeconds(words[1], kMaxFaultS);
    if (!seconds) return error(fmt::format("seconds must be a number in [0, {:g}]", kMaxFaultS));
    device_.PowerCycle();
    const int ended = EndAll(Instrument::kEpc, "", id);
    Faults& faults = faults_[static_cast<int>(Instrument::kEpc)];
    faults.unreachable_until_ns = std::max(faults.unreachable_until_ns, now_ns + SecondsToNs(*seconds));
    faults.unreachable_reason = "power cycle";
    return ok(fmt::format("powercycle: every channel at 0 V, {} session{} ended, the EPC unreachable for {:g} s", ended,
                          ended == 1 ? "" : "s", *seconds));
  }
  if (command == "temperature") {
    if (words.size() != 2) return usage("temperature <celsius>");
    double celsius = 0.0;
    if (ParseNumber(words[1], &celsius) != NumberParse::kOk) return error("temperature must be a finite number");
    if (std::string problem = device_.SetTemperature(celsius); !problem.empty()) return error("temperature: " + problem);
    return ok(fmt::format("temperature {:g} C", celsius));
  }
  if (command == "wavelength") {
    if (words.size() != 2) return usage("wavelength <nm>");
    double nm = 0.0;
    if (ParseNumber(words[1], &nm) != NumberParse::kOk) return error("wavelength must be a finite number");
    if (std::string problem = device_.SetWavelength(nm); !problem.empty()) return error("wavelength: " + problem);
    return ok(fmt::format("wavelength {:g} nm", nm));
  }
  return error("unknown command; " + ControlHelp());
}

bool EmulatorCore::Reply(SessionId id, Session& session, std::string reply, int64_t now_ns) {
  int64_t due_ns = now_ns;
  std::string bytes;
  if (session.instrument == Instrument::kControl) {
    bytes = std::move(reply) + "\n";
  } else {
    Faults& faults = faults_[static_cast<int>(session.instrument)];
    due_ns += latency_ns_;
    if (faults.slow > 0) {
      --faults.slow;
      due_ns += SecondsToNs(faults.slow_s);
    }
    if (faults.garbage > 0) {
      --faults.garbage;
      bytes = Garbage();
    } else if (faults.truncate > 0) {
      --faults.truncate;
      bytes = reply.substr(0, reply.size() / 2);
    } else {
      bytes = std::move(reply) + "\n";
    }
  }
  if (session.pending_bytes + session.out.size() + bytes.size() > kMaxQueuedBytes) {
    End(id, fmt::format("a {} client does not read its replies: {} bytes queued, disconnected",
                        InstrumentName(session.instrument), session.pending_bytes + session.out.size()));
    return false;
  }
  due_ns = std::max(due_ns, session.last_due_ns);  // in the order of the queries
  session.last_due_ns = due_ns;
  if (due_ns <= now_ns && session.pending.empty()) {
    session.out += bytes;
  } else {
    session.pending_bytes += bytes.size();
    session.pending.push_back(PendingReply{due_ns, std::move(bytes)});
  }
  return true;
}

std::string EmulatorCore::Garbage() {
  const int length = 8 + static_cast<int>(garbage_random_.Uniform() * 33.0);
  std::string junk;
  for (int i = 0; i < length; ++i) {
    junk.push_back(kGarbageAlphabet[static_cast<size_t>(garbage_random_.Uniform() * kGarbageAlphabet.size())]);
  }
  return junk + "\n";
}

std::string_view EmulatorCore::Output(SessionId id, int64_t now_ns) {
  auto it = sessions_.find(id);
  if (it == sessions_.end()) return {};
  PumpStream(id, it->second, now_ns);
  it = sessions_.find(id);  // a client that does not read is ended by its stream
  if (it == sessions_.end()) return {};
  Session& session = it->second;
  while (!session.pending.empty() && session.pending.front().due_ns <= now_ns) {
    session.pending_bytes -= session.pending.front().bytes.size();
    session.out += session.pending.front().bytes;
    session.pending.pop_front();
  }
  return session.out;
}

void EmulatorCore::Written(SessionId id, size_t bytes) {
  const auto it = sessions_.find(id);
  if (it == sessions_.end()) return;
  it->second.out.erase(0, std::min(bytes, it->second.out.size()));
}

int64_t EmulatorCore::NextDueNs() const {
  int64_t next = std::numeric_limits<int64_t>::max();
  for (const auto& [id, session] : sessions_) {
    if (!session.pending.empty()) next = std::min(next, session.pending.front().due_ns);
    if (!session.stream_query.empty()) next = std::min(next, session.next_stream_ns);
  }
  return next;
}

nlohmann::ordered_json EmulatorCore::Status(int64_t now_ns) const {
  nlohmann::ordered_json status;
  status["time_s"] = static_cast<double>(now_ns - start_ns_) * 1e-9;
  status["temperature_c"] = device_.temperature_c();
  status["wavelength_nm"] = device_.wavelength_nm();
  nlohmann::ordered_json channels = nlohmann::ordered_json::array();
  for (int c = 0; c < device_.channel_count(); ++c) {
    channels.push_back({{"set_v", device_.set_v(c)}, {"effective_v", device_.effective_v(c)}});
  }
  status["channels"] = std::move(channels);
  status["s_in"] = Vector(device_.s_in());
  status["s_out"] = Vector(device_.s_out());
  status["input_steps"] = device_.input_steps();
  status["input_steps_skipped"] = device_.input_steps_skipped();
  for (Instrument instrument : {Instrument::kEpc, Instrument::kPolarimeter, Instrument::kControl}) {
    const Counters& c = counters_[static_cast<int>(instrument)];
    const auto open = std::count_if(sessions_.begin(), sessions_.end(),
                                    [&](const auto& entry) { return entry.second.instrument == instrument; });
    nlohmann::ordered_json counts;
    if (instrument == Instrument::kControl) {
      counts["commands"] = c.queries;
    } else {
      counts["queries"] = c.queries;
      if (instrument == Instrument::kEpc) counts["sets"] = c.sets;
      if (instrument == Instrument::kPolarimeter) {
        counts["streamed"] = c.streamed;
        counts["stream_skipped"] = c.stream_skipped;
      }
    }
    counts["errors"] = c.errors;
    counts["connections"] = {
        {"open", open}, {"accepted", c.accepted}, {"refused", c.refused}, {"ended", c.ended}};
    status[InstrumentName(instrument)] = std::move(counts);
  }
  nlohmann::ordered_json faults = nlohmann::ordered_json::array();
  for (Instrument instrument : {Instrument::kEpc, Instrument::kPolarimeter}) {
    const Faults& f = faults_[static_cast<int>(instrument)];
    const char* name = InstrumentName(instrument);
    if (f.garbage > 0) faults.push_back({{"instrument", name}, {"fault", "garbage"}, {"replies", f.garbage}});
    if (f.truncate > 0) faults.push_back({{"instrument", name}, {"fault", "truncate"}, {"replies", f.truncate}});
    if (f.slow > 0) {
      faults.push_back({{"instrument", name}, {"fault", "slow"}, {"replies", f.slow}, {"seconds", f.slow_s}});
    }
    if (now_ns < f.unreachable_until_ns) {
      faults.push_back({{"instrument", name},
                        {"fault", "unreachable"},
                        {"reason", f.unreachable_reason},
                        {"remaining_s", static_cast<double>(f.unreachable_until_ns - now_ns) * 1e-9}});
    }
  }
  status["faults"] = std::move(faults);
  return status;
}

}  // namespace dpc::services
