#include "calibrate_command.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <cstdlib>
#include <functional>
#include <sys/wait.h>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <thread>

#include "bus_tool_support.h"
#include "calibration.h"
#include "dpc/cli/command_line.h"
#include "dpc/cli/scenario_loading.h"
#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_validation.h"
#include "dpc/instrument/line_link.h"
#include "dpc/optics/waveplate_chain.h"
#include "dpc/scenario_io/scenario_writer.h"

namespace dpc::tools {
namespace {

using json = nlohmann::ordered_json;
constexpr double kDegPerRad = 180.0 / M_PI;
/// The inputs of a voltage's readings must span more than a line: the middle singular value of
/// their cross-covariance at least this share of the largest.
constexpr double kMinSpread = 0.02;
/// A voltage's readings are taken over at most this many dwells before the input is deemed still
/// (a slow scrambler's input can stay nearly still for half a second: seen with the emulator's
/// 20 rad/s).
constexpr int kMaxDwells = 16;

struct Failure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// The EPC and the polarimeter, spoken to directly (the bench's services must not run).
class Instruments {
 public:
  explicit Instruments(const ScenarioConfig& scenario)
      : epc_config_(*scenario.waveplate_device),
        meter_config_(*scenario.polarimeter_device),
        epc_(epc_config_.link),
        meter_(meter_config_.link) {}

  void Open() {
    if (std::string why = epc_.Open(2.0); !why.empty()) throw Failure("the EPC (" + epc_.Describe() + "): " + why);
    if (std::string why = meter_.Open(2.0); !why.empty()) {
      throw Failure("the polarimeter (" + meter_.Describe() + "): " + why);
    }
  }

  /// Sets control `index` (0-based) to `volts` (quantized); the DAC's voltage.
  double Set(int index, double volts) {
    const instrument::DacPoint dac =
        instrument::Quantize(volts, epc_config_.volts_min, epc_config_.volts_max, epc_config_.dac_bits);
    const int channel = epc_config_.channels.empty() ? index + 1 : epc_config_.channels[static_cast<size_t>(index)];
    const std::string line = FormatSetCommand(epc_config_.set_command, channel, dac.volts, dac.code);
    std::string why;
    if (std::string failure = epc_.WriteLine(line, epc_config_.link.response_timeout_s); !failure.empty()) {
      throw Failure(fmt::format("the EPC: {}: {}", line, failure));
    }
    if (!epc_config_.ack.empty()) {
      const auto reply = epc_.ReadLine(epc_config_.link.response_timeout_s, &why);
      if (!reply || *reply != epc_config_.ack) {
        throw Failure(fmt::format("the EPC: {}: {}", line, reply ? "answered \"" + reply->substr(0, 60) + "\"" : why));
      }
    }
    return dac.volts;
  }

  /// One pair of simultaneous SOPs; a refused or late reply is retried a few times.
  std::pair<StokesVector, StokesVector> Read() {
    std::string why;
    for (int attempt = 0; attempt < 5; ++attempt) {
      const auto reply = meter_.Query(meter_config_.query, meter_config_.link.response_timeout_s, &why);
      if (!reply) continue;
      StokesVector s[2];
      why = instrument::ParseStokesReply(*reply, 2, meter_config_.min_dop, s);
      if (why.empty()) return {s[0], s[1]};
    }
    throw Failure("the polarimeter: " + why);
  }

 private:
  WaveplateDeviceConfig epc_config_;
  PolarimeterDeviceConfig meter_config_;
  instrument::LineLink epc_, meter_;
};

/// One stage's sweep: the voltages set (the DAC's) and the chain's rotation at each.
struct Sweep {
  std::vector<double> volts;
  std::vector<Matrix3> rotations;
};


/// What one condition's sweeps gave: each stage's table and how well the model fits.
struct ConditionResult {
  std::vector<ControlMapConfig> tables;  ///< per stage, kTable
  json stage_reports = json::array();
  double sum_squares_rad2 = 0.0;         ///< over the measured rotations: the model's angle off each
  double worst_rad = 0.0;
  size_t rotations = 0;
};

/// "15 °C", "1550 nm".
std::string ConditionText(ControlMapConfig::Condition condition, double value) {
  return fmt::format("{:g} {}", value, ConditionUnit(condition));
}

/// Each stage swept through its range at the condition the device is at now, and its table fitted.
ConditionResult MeasureAndFit(const ScenarioConfig& scenario, const CalibrateOptions& o, Instruments& instruments,
                              const std::function<void(const std::string&)>& status, const std::string& label) {
  const int stages = static_cast<int>(scenario.stages.size());
  std::vector<double> reference(static_cast<size_t>(stages));
  for (int i = 0; i < stages; ++i) {
    reference[static_cast<size_t>(i)] = scenario.stages[static_cast<size_t>(i)].range->Clamp(o.reference_v);
  }
  // The device's own settling time is the least to wait after a set.
  const double settle_s = std::max(o.settle_s, scenario.waveplate_device->settling_s);
  /// The chain's rotation now: `readings` pairs spread over the dwell, Kabsch. If the input
  /// hardly moved in that time (a scrambler's pace varies), more dwells' pairs are added.
  const auto measure = [&]() {
    std::vector<StokesVector> in, out;
    const auto pause = std::chrono::duration<double>(o.dwell_s / o.readings);
    double spread = 0.0;
    for (int dwell = 0; dwell < kMaxDwells; ++dwell) {
      for (int k = 0; k < o.readings; ++k) {
        if (StopSignals::requested()) throw Failure("stopped by a signal");
        const auto [s_in, s_out] = instruments.Read();
        in.push_back(s_in);
        out.push_back(s_out);
        std::this_thread::sleep_for(pause);
      }
      const Matrix3 rotation = FitRotation(in, out, &spread);
      if (spread >= kMinSpread) return rotation;
    }
    throw Failure(fmt::format("the input SOP hardly moved during {} dwells of {:g} s ({:.3g} of {} pairs spread): "
                              "the rotation cannot be fitted; let the input move (a scrambler before the EPC) or "
                              "lengthen --dwell-s",
                              kMaxDwells, o.dwell_s, spread, in.size()));
  };

  std::vector<Sweep> sweeps(static_cast<size_t>(stages));
  for (int i = 0; i < stages; ++i) reference[static_cast<size_t>(i)] = instruments.Set(i, reference[static_cast<size_t>(i)]);
  std::this_thread::sleep_for(std::chrono::duration<double>(settle_s));
  const Matrix3 at_reference = measure();
  for (int i = 0; i < stages; ++i) {
    const ControlRange& range = *scenario.stages[static_cast<size_t>(i)].range;
    Sweep& sweep = sweeps[static_cast<size_t>(i)];
    for (int k = 0; k < o.points; ++k) {
      const double wanted = range.min + (range.max - range.min) * k / (o.points - 1);
      sweep.volts.push_back(instruments.Set(i, wanted));
      std::this_thread::sleep_for(std::chrono::duration<double>(settle_s));
      sweep.rotations.push_back(measure());
      status(fmt::format("dpc calibrate: {}stage {} of {} ({}), {} of {} voltages", label, i + 1, stages,
                         scenario.stages[static_cast<size_t>(i)].name, k + 1, o.points));
    }
    instruments.Set(i, reference[static_cast<size_t>(i)]);
  }

  // Each stage's retardance relative to the reference, about its (fixed) image axis.
  std::vector<std::vector<double>> relative(static_cast<size_t>(stages));
  for (int i = 0; i < stages; ++i) {
    const Sweep& sweep = sweeps[static_cast<size_t>(i)];
    Vector3 axis_sum = Vector3::Zero();
    std::vector<Matrix3> relative_rotations;
    for (const Matrix3& m : sweep.rotations) {
      relative_rotations.push_back(m * at_reference.transpose());
      if (const auto axis = RotationAxis(relative_rotations.back())) {
        axis_sum += axis_sum.dot(*axis) < 0 ? Vector3(-*axis) : *axis;
      }
    }
    if (axis_sum.norm() < 1e-9) {
      throw Failure(fmt::format("{}stage {} ({}) hardly turned the output over its range: no retardance measured",
                                label, i + 1, scenario.stages[static_cast<size_t>(i)].name));
    }
    const Vector3 axis = axis_sum.normalized();
    std::vector<double>& psi = relative[static_cast<size_t>(i)];
    for (const Matrix3& r : relative_rotations) psi.push_back(SignedAngleAbout(r, axis));
    Unwrap(&psi);
    // Zero at the reference voltage (interpolated between the nearest sweep points).
    const auto& v = sweep.volts;
    const double at_ref = [&] {
      const double ref = reference[static_cast<size_t>(i)];
      for (size_t k = 1; k < v.size(); ++k) {
        if (ref <= v[k]) {
          const double f = v[k] > v[k - 1] ? (ref - v[k - 1]) / (v[k] - v[k - 1]) : 0.0;
          return psi[k - 1] + f * (psi[k] - psi[k - 1]);
        }
      }
      return psi.back();
    }();
    for (double& p : psi) p -= at_ref;
  }

  // The absolute retardances: the offsets at the reference and the sign of each relative curve
  // (the image axis's sign is arbitrary) that make the model chain reproduce every measured
  // rotation, by Gauss-Newton from zero for each sign combination.
  std::vector<StageConfig> unit_stages = scenario.stages;
  for (StageConfig& s : unit_stages) {
    s.map = ControlMapConfig{};
    s.map.rad_per_unit = 1.0;  // θ = φ: the model takes retardances
    s.range.reset();
  }
  const WaveplateChain unit_chain = BuildChain(unit_stages);
  const auto rotation_of = [&](const ControlVector& theta) {
    ChainPose pose;
    unit_chain.ComputePose(theta, &pose);
    return unit_chain.MuellerMatrix(pose);
  };
  struct Measurement {
    int stage = -1;      ///< the stage moved (−1: the reference)
    double volts = 0.0;  ///< its voltage
    double psi = 0.0;    ///< its retardance relative to the reference
    Matrix3 rotation;
  };
  std::vector<Measurement> data{{-1, 0.0, 0.0, at_reference}};
  for (int i = 0; i < stages; ++i) {
    const Sweep& sweep = sweeps[static_cast<size_t>(i)];
    for (size_t k = 0; k < sweep.rotations.size(); ++k) {
      data.push_back({i, sweep.volts[k], relative[static_cast<size_t>(i)][k], sweep.rotations[k]});
    }
  }
  const auto theta_of = [&](const Measurement& m, const Eigen::VectorXd& offsets, const std::vector<double>& sign) {
    ControlVector theta = offsets;
    if (m.stage >= 0) theta[m.stage] += sign[static_cast<size_t>(m.stage)] * m.psi;
    return theta;
  };
  const auto residuals = [&](const Eigen::VectorXd& offsets, const std::vector<double>& sign) {
    Eigen::VectorXd r(static_cast<Eigen::Index>(data.size() * 9));
    for (size_t d = 0; d < data.size(); ++d) {
      const Matrix3 diff = rotation_of(theta_of(data[d], offsets, sign)) - data[d].rotation;
      for (int e = 0; e < 9; ++e) r[static_cast<Eigen::Index>(d * 9 + static_cast<size_t>(e))] = diff(e / 3, e % 3);
    }
    return r;
  };
  Eigen::VectorXd best_offsets = Eigen::VectorXd::Zero(stages);
  std::vector<double> best_sign(static_cast<size_t>(stages), 1.0);
  double best_cost = INFINITY;
  for (int combination = 0; combination < (1 << stages); ++combination) {
    std::vector<double> sign(static_cast<size_t>(stages));
    for (int i = 0; i < stages; ++i) sign[static_cast<size_t>(i)] = (combination >> i) & 1 ? -1.0 : 1.0;
    Eigen::VectorXd offsets = Eigen::VectorXd::Zero(stages);
    for (int iteration = 0; iteration < 30; ++iteration) {
      const Eigen::VectorXd r = residuals(offsets, sign);
      Eigen::MatrixXd jacobian(r.size(), stages);
      for (int i = 0; i < stages; ++i) {
        Eigen::VectorXd moved = offsets;
        moved[i] += 1e-6;
        jacobian.col(i) = (residuals(moved, sign) - r) / 1e-6;
      }
      const Eigen::VectorXd step = jacobian.colPivHouseholderQr().solve(-r);
      offsets += step;
      for (int i = 0; i < stages; ++i) offsets[i] = std::remainder(offsets[i], 2 * M_PI);
      if (step.norm() < 1e-10) break;
    }
    const double cost = residuals(offsets, sign).squaredNorm();
    if (cost < best_cost) {
      best_cost = cost;
      best_offsets = offsets;
      best_sign = sign;
    }
  }

  // Per stage: the retardance against volts, a polynomial through it, monotonic over the range,
  // and the table taken from it at the swept voltages.
  ConditionResult result;
  std::vector<ScaledPolynomial> fits;
  for (int i = 0; i < stages; ++i) {
    const Sweep& sweep = sweeps[static_cast<size_t>(i)];
    std::vector<double> theta;
    for (const double p : relative[static_cast<size_t>(i)]) theta.push_back(best_offsets[i] + best_sign[static_cast<size_t>(i)] * p);
    const ScaledPolynomial fit = FitPolynomial(sweep.volts, theta, std::min(o.degree, o.points - 2));
    double sum_squares = 0.0, worst = 0.0;
    for (size_t k = 0; k < theta.size(); ++k) {
      const double e = std::abs(fit(sweep.volts[k]) - theta[k]);
      sum_squares += e * e;
      worst = std::max(worst, e);
    }
    const ControlRange& range = *scenario.stages[static_cast<size_t>(i)].range;
    const double slope_sign = fit.Derivative((range.min + range.max) / 2) >= 0 ? 1.0 : -1.0;
    for (int k = 0; k <= 200; ++k) {
      const double v = range.min + (range.max - range.min) * k / 200.0;
      if (fit.Derivative(v) * slope_sign <= 0.0) {
        throw Failure(fmt::format("{}stage {} ({}): the retardance is not monotonic in the voltage near {:.3g} V (a "
                                  "lookup table needs it to be); narrow the stage's range or lower --degree",
                                  label, i + 1, scenario.stages[static_cast<size_t>(i)].name, v));
      }
    }
    ControlMapConfig map;
    map.kind = ControlMapConfig::Kind::kTable;
    for (const double v : sweep.volts) {
      if (!map.table_control.empty() && v <= map.table_control.back()) continue;  // DAC steps that coincide
      map.table_control.push_back(v);
      map.table_angle_rad.push_back(fit(v));
    }
    result.tables.push_back(map);
    fits.push_back(fit);
    result.stage_reports.push_back(
        {{"name", scenario.stages[static_cast<size_t>(i)].name},
         {"points", map.table_control.size()},
         {"offset_at_reference_deg", best_offsets[i] * kDegPerRad},
         {"retardance_at_min_deg", fit(range.min) * kDegPerRad},
         {"retardance_at_max_deg", fit(range.max) * kDegPerRad},
         {"fit_residual_rms_deg", std::sqrt(sum_squares / static_cast<double>(theta.size())) * kDegPerRad},
         {"fit_residual_max_deg", worst * kDegPerRad}});
  }
  // The whole model against every measured rotation (the angle between them).
  for (const Measurement& m : data) {
    ControlVector theta(stages);
    for (int i = 0; i < stages; ++i) theta[i] = fits[static_cast<size_t>(i)](reference[static_cast<size_t>(i)]);
    if (m.stage >= 0) theta[m.stage] = fits[static_cast<size_t>(m.stage)](m.volts);
    const Matrix3 error = rotation_of(theta) * m.rotation.transpose();
    const double angle = std::acos(std::clamp((error.trace() - 1) / 2, -1.0, 1.0));
    result.sum_squares_rad2 += angle * angle;
    result.worst_rad = std::max(result.worst_rad, angle);
  }
  result.rotations = data.size();
  return result;
}

/// Brings the device to `value` (°C or nm): the condition command with {value} replaced, or the
/// person at the terminal; then waits the settle time.
void BringToCondition(const CalibrateOptions& o, ControlMapConfig::Condition condition, double value) {
  const std::string text = ConditionText(condition, value);
  if (!o.condition_command.empty()) {
    std::string command = o.condition_command;
    const std::string number = fmt::format("{:g}", value);
    for (size_t at = command.find("{value}"); at != std::string::npos; at = command.find("{value}", at + number.size())) {
      command.replace(at, 7, number);
    }
    fmt::print(stderr, "dpc calibrate: to {}: {}\n", text, command);
    // Its output goes to stderr with the progress (stdout carries the result, e.g. --json).
    const int status = std::system(("exec 1>&2; " + command).c_str());
    if (StopSignals::requested()) throw Failure("stopped by a signal");
    if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      throw Failure(fmt::format("the condition command for {} failed ({}): {}", text,
                                status == -1                ? std::string("could not run it")
                                : WIFEXITED(status)         ? fmt::format("exit status {}", WEXITSTATUS(status))
                                                            : std::string("killed by a signal"),
                                command));
    }
  } else {
    fmt::print(stderr, "dpc calibrate: bring the device to {}, then press Enter (Ctrl-C stops) ", text);
    std::string line;
    if (!std::getline(std::cin, line)) throw Failure("no answer on the terminal");
  }
  std::this_thread::sleep_for(std::chrono::duration<double>(o.condition_settle_s));
}

}  // namespace

CLI::App* AddCalibrateCommand(CLI::App& app, CalibrateOptions* o) {
  CLI::App* calibrate = app.add_subcommand(
      "calibrate",
      "Measure a real EPC's control maps with the real polarimeter (the scenario's waveplate_device and "
      "polarimeter_device, reply S_IN_AND_S_OUT; the bench stopped) and write the scenario with them, optionally "
      "at several temperatures or wavelengths");
  calibrate->add_option("scenario", o->scenario_path, "The bench's scenario, with both instruments")
      ->required()
      ->check(CLI::ExistingFile);
  calibrate->add_option("-o,--output", o->output_path, "The calibrated scenario to write")->required();
  calibrate->add_option("--points", o->points, "Voltages per stage over its range")
      ->check(CLI::Range(5, 1000))
      ->capture_default_str();
  calibrate->add_option("--readings", o->readings, "SOP pairs per voltage")->check(CLI::Range(3, 1000))->capture_default_str();
  calibrate->add_option("--dwell-s", o->dwell_s, "The readings of a voltage are spread over this long")
      ->check(cli::NumberIn(0.0, 10.0))
      ->capture_default_str();
  calibrate->add_option("--settle-s", o->settle_s, "Wait after setting a voltage")
      ->check(cli::NumberIn(0.0, 10.0))
      ->capture_default_str();
  calibrate->add_option("--reference-v", o->reference_v, "The other channels' voltage during a sweep")
      ->capture_default_str();
  calibrate->add_option("--degree", o->degree, "Degree of the polynomial each table is taken from")
      ->check(CLI::Range(1, 9))
      ->capture_default_str();
  CLI::Option* temperatures =
      calibrate
          ->add_option("--temperatures-c", o->temperatures_c,
                       "Calibrate at each of these temperatures (°C, 2 to 16, comma-separated): each stage's map "
                       "becomes tables keyed by temperature, interpolated at the operating temperature")
          ->delimiter(',')
          ->check(cli::NumberIn(-100.0, 200.0));
  CLI::Option* wavelengths =
      calibrate
          ->add_option("--wavelengths-nm", o->wavelengths_nm,
                       "Calibrate at each of these wavelengths (nm, 2 to 16, comma-separated): tables keyed by "
                       "wavelength, interpolated in 1/λ at the operating wavelength")
          ->delimiter(',')
          ->check(cli::NumberIn(100.0, 10000.0));
  temperatures->excludes(wavelengths);
  calibrate
      ->add_option("--condition-command", o->condition_command,
                   "A shell command that brings the device to each condition before its sweeps ({value} is replaced "
                   "by the temperature or wavelength; it must exit 0), e.g. a TEC controller's or a tunable laser's "
                   "client; without it, dpc calibrate asks at the terminal");
  calibrate->add_option("--condition-settle-s", o->condition_settle_s,
                        "Wait after bringing the device to a condition, before its sweeps")
      ->check(cli::NumberIn(0.0, 3600.0))
      ->capture_default_str();
  CLI::Option* operating_temperature =
      calibrate->add_option("--operating-temperature-c", o->operating_point,
                            "The temperature the written scenario runs at (default: the first of --temperatures-c)")
          ->needs(temperatures);
  CLI::Option* operating_wavelength =
      calibrate->add_option("--operating-wavelength-nm", o->operating_point,
                            "The wavelength the written scenario runs at (default: the first of --wavelengths-nm)")
          ->needs(wavelengths);
  operating_temperature->excludes(operating_wavelength);
  calibrate->add_flag("--json", o->json, "Print the result as one JSON object");
  return calibrate;
}

cli::ExitCode RunCalibrateCommand(const CalibrateOptions& o) {
  ScenarioConfig scenario;
  try {
    scenario = cli::LoadScenarioWithOverrides(o.scenario_path, {}, PaperScenario("131"));
    ValidateScenario(scenario);
  } catch (const ScenarioError& e) {
    fmt::print(stderr, "dpc calibrate: {}: {}\n", o.scenario_path, cli::DescribeScenarioError(e, {}));
    return cli::ExitCode::kInvalidInput;
  }
  const auto refuse = [&](const std::string& why) {
    fmt::print(stderr, "dpc calibrate: {}: {}\n", o.scenario_path, why);
    return cli::ExitCode::kInvalidInput;
  };
  if (!scenario.waveplate_device) return refuse("no waveplate_device: nothing to calibrate");
  if (!scenario.polarimeter_device) return refuse("no polarimeter_device to measure with");
  if (scenario.polarimeter_device->reply != PolarimeterDeviceConfig::Reply::kInputAndOutput) {
    return refuse("the polarimeter must measure both SOPs (polarimeter_device.reply: S_IN_AND_S_OUT): the chain's "
                  "whole rotation at each voltage is fitted from input and output pairs");
  }
  for (size_t i = 0; i < scenario.stages.size(); ++i) {
    if (scenario.stages[i].kind != StageConfig::Kind::kFixedAxis) {
      return refuse(fmt::format("stages[{}] has an adjustable axis: only fixed-axis stages are calibrated", i));
    }
  }
  // The conditions, ascending (a thermal ramp; the tables' order), or none.
  const bool by_wavelength = !o.wavelengths_nm.empty();
  const ControlMapConfig::Condition key =
      by_wavelength ? ControlMapConfig::Condition::kWavelengthNm : ControlMapConfig::Condition::kTemperatureC;
  std::vector<double> conditions = by_wavelength ? o.wavelengths_nm : o.temperatures_c;
  std::sort(conditions.begin(), conditions.end());
  if (conditions.empty() && !o.condition_command.empty()) {
    return refuse("--condition-command without --temperatures-c or --wavelengths-nm: no condition to bring it to");
  }
  if (!conditions.empty()) {
    const char* option = by_wavelength ? "--wavelengths-nm" : "--temperatures-c";
    if (conditions.size() < 2 || conditions.size() > static_cast<size_t>(ControlMapConfig::kMaxConditionTables)) {
      return refuse(fmt::format("{}: {} value(s); give 2 to {} (one condition needs no key: leave the option out)",
                                option, conditions.size(), ControlMapConfig::kMaxConditionTables));
    }
    if (std::adjacent_find(conditions.begin(), conditions.end()) != conditions.end()) {
      return refuse(fmt::format("{}: a condition is given twice", option));
    }
    if (o.operating_point && (*o.operating_point < conditions.front() || *o.operating_point > conditions.back())) {
      return refuse(fmt::format("the operating point {} is outside the calibrated {}–{}: a calibration is not "
                                "extrapolated",
                                ConditionText(key, *o.operating_point), conditions.front(),
                                ConditionText(key, conditions.back())));
    }
    if (o.condition_command.empty() && isatty(STDIN_FILENO) != 1) {
      return refuse(fmt::format("{} needs --condition-command (how the device is brought to each condition) or a "
                                "terminal to ask at",
                                option));
    }
  }

  StopSignals signals;
  Instruments instruments(scenario);
  const bool on_terminal = isatty(STDERR_FILENO) == 1;
  const auto status = [&](const std::string& line) {
    if (on_terminal) {
      fmt::print(stderr, "\r\x1b[K{}", line);
    } else {
      fmt::print(stderr, "{}\n", line);
    }
  };
  std::vector<ConditionResult> results;
  try {
    instruments.Open();
    if (conditions.empty()) {
      results.push_back(MeasureAndFit(scenario, o, instruments, status, ""));
    } else {
      for (size_t c = 0; c < conditions.size(); ++c) {
        if (on_terminal) fmt::print(stderr, "\r\x1b[K");
        BringToCondition(o, key, conditions[c]);
        results.push_back(MeasureAndFit(scenario, o, instruments, status,
                                        fmt::format("{} ({} of {}), ", ConditionText(key, conditions[c]), c + 1,
                                                    conditions.size())));
      }
    }
    if (on_terminal) fmt::print(stderr, "\r\x1b[K");
  } catch (const Failure& e) {
    if (on_terminal) fmt::print(stderr, "\n");
    fmt::print(stderr, "dpc calibrate: {}\n", e.what());
    return StopSignals::requested() ? cli::ExitCode::kOk : cli::ExitCode::kRuntimeError;
  }

  // The calibrated maps: the one table per stage, or the tables keyed by condition.
  ScenarioConfig calibrated = scenario;
  const double operating_point = conditions.empty() ? 0.0 : o.operating_point.value_or(conditions.front());
  for (size_t i = 0; i < scenario.stages.size(); ++i) {
    ControlMapConfig& map = calibrated.stages[i].map;
    if (conditions.empty()) {
      map = results.front().tables[i];
      continue;
    }
    map = ControlMapConfig{};
    map.kind = ControlMapConfig::Kind::kTablesByCondition;
    map.condition = key;
    map.operating_point = operating_point;
    for (size_t c = 0; c < conditions.size(); ++c) {
      map.condition_tables.push_back(
          {conditions[c], results[c].tables[i].table_control, results[c].tables[i].table_angle_rad});
    }
  }
  double sum_squares = 0.0, worst = 0.0;
  size_t rotations = 0;
  for (const ConditionResult& r : results) {
    sum_squares += r.sum_squares_rad2;
    worst = std::max(worst, r.worst_rad);
    rotations += r.rotations;
  }
  const auto rms_deg = [](double squares, size_t count) {
    return std::sqrt(squares / static_cast<double>(count)) * kDegPerRad;
  };
  json report;
  report["scenario"] = o.scenario_path;
  if (conditions.empty()) {
    report["stages"] = results.front().stage_reports;
  } else {
    json per_condition = json::array();
    for (size_t c = 0; c < conditions.size(); ++c) {
      per_condition.push_back({{ConditionKeyName(key), conditions[c]},
                               {"stages", results[c].stage_reports},
                               {"model_residual_rms_deg", rms_deg(results[c].sum_squares_rad2, results[c].rotations)},
                               {"model_residual_max_deg", results[c].worst_rad * kDegPerRad},
                               {"rotations_measured", results[c].rotations}});
    }
    report["conditions"] = per_condition;
    report[std::string("operating_") + ConditionKeyName(key)] = operating_point;
  }
  report["model_residual_rms_deg"] = rms_deg(sum_squares, rotations);
  report["model_residual_max_deg"] = worst * kDegPerRad;
  report["rotations_measured"] = rotations;

  char when[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(when, sizeof when, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  const std::string at_conditions =
      conditions.empty() ? ""
                         : fmt::format(" at {} {}, operating at {}",
                                       fmt::join(conditions, ", "), ConditionUnit(key),
                                       ConditionText(key, operating_point));
  calibrated.description =
      fmt::format("{} (maps calibrated by dpc calibrate{}, {}: model residual {:.3f}° rms)", scenario.description,
                  at_conditions, when, report["model_residual_rms_deg"].get<double>());
  try {
    ValidateScenario(calibrated);
    std::ofstream out(o.output_path);
    out << ScenarioToText(calibrated);
    if (!out) throw std::runtime_error("cannot write " + o.output_path);
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc calibrate: {}\n", e.what());
    return cli::ExitCode::kRuntimeError;
  }
  report["output"] = o.output_path;
  if (o.json) {
    std::cout << report.dump() << std::endl;
    return cli::ExitCode::kOk;
  }
  const auto print_stages = [](const json& stage_reports) {
    for (const json& s : stage_reports) {
      fmt::print("stage {:<8} {:>3} points, {:8.1f}° … {:8.1f}° over the range, offset {:6.2f}°, fit residual {:.3f}° rms "
                 "({:.3f}° max)\n",
                 s["name"].get<std::string>(), s["points"].get<int>(), s["retardance_at_min_deg"].get<double>(),
                 s["retardance_at_max_deg"].get<double>(), s["offset_at_reference_deg"].get<double>(),
                 s["fit_residual_rms_deg"].get<double>(), s["fit_residual_max_deg"].get<double>());
    }
  };
  if (conditions.empty()) {
    print_stages(report["stages"]);
  } else {
    for (size_t c = 0; c < conditions.size(); ++c) {
      const json& at = report["conditions"][c];
      fmt::print("at {}: model against {} measured rotations: {:.3f}° rms, {:.3f}° max\n",
                 ConditionText(key, conditions[c]), at["rotations_measured"].get<size_t>(),
                 at["model_residual_rms_deg"].get<double>(), at["model_residual_max_deg"].get<double>());
      print_stages(at["stages"]);
    }
  }
  fmt::print("model against {} measured rotations: {:.3f}° rms, {:.3f}° max{} → {}\n", rotations,
             report["model_residual_rms_deg"].get<double>(), report["model_residual_max_deg"].get<double>(),
             conditions.empty() ? "" : fmt::format(" (tables by {}, operating at {})",
                                                   ConditionNoun(key),
                                                   ConditionText(key, operating_point)),
             o.output_path);
  return cli::ExitCode::kOk;
}

}  // namespace dpc::tools
