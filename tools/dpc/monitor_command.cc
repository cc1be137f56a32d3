#include "monitor_command.h"

#include <fmt/format.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <numbers>
#include <thread>

#include "bus_messages.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/config/scenario_builders.h"
#include "dpc/cli/command_line.h"
#include "dpc/cli/exit_code.h"

namespace dpc::tools {
namespace {

namespace fdds = eprosima::fastdds::dds;
using Clock = std::chrono::steady_clock;

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

/// The terminal's width now (it may have been resized), else $COLUMNS, else 80. One column is
/// left free: a line that fills the last column wraps on some terminals.
int TerminalColumns() {
  winsize size{};
  if (ioctl(STDOUT_FILENO, TIOCGWINSZ, &size) == 0 && size.ws_col > 0) return std::max(20, size.ws_col - 1);
  if (const char* columns = std::getenv("COLUMNS"); columns != nullptr) {
    const int n = std::atoi(columns);
    if (n > 20) return n - 1;
  }
  return 79;
}

}  // namespace

// ---- MonitorState

void MonitorState::OnSample(const msg::StokesSample& sample) {
  ++period_samples_;
  ++total_samples_;
  if (!target_) return;
  const StokesVector s_out = bus::ToStokes(sample.s_out());
  if (!s_out.allFinite()) return;
  const double error_deg = target_->DistanceRad(s_out.normalized()) * kDegPerRad;
  if (!std::isfinite(error_deg)) return;
  ++period_errors_;
  period_error_sum_deg_ += error_deg;
  period_error_max_deg_ = period_errors_ == 1 ? error_deg : std::max(period_error_max_deg_, error_deg);
}

void MonitorState::OnState(const msg::WaveplateState& state) {
  have_state_ = true;
  phi_applied_ = state.phi_applied();
  active_ = state.mode() == msg::DRIVER_ACTIVE;
  reason_ = state.reason().to_string();
  obeyed_id_ = state.obeyed_controller_id().to_string();
  obeyed_priority_ = state.obeyed_priority();
}

void MonitorState::OnStatus(const msg::ControllerStatus& status) {
  Controller& c = controllers_[status.controller_id().to_string()];
  c.missed_deadlines = status.missed_deadlines();
  c.condition = status.condition().to_string();
}

void MonitorState::OnTarget(const msg::Target& target) {
  if (target.revision() < target_revision_) return;  // an older sample arriving late
  target_revision_ = target.revision();
  BenchTarget read;
  if (std::string problem = bus::ReadTarget(target, &read); !problem.empty()) {
    target_.reset();
    target_problem_ = problem;
    return;
  }
  target_ = BuildTarget(read.target);
  target_problem_.clear();
}

size_t DisplayWidth(const std::string& text) {
  size_t width = 0;
  for (unsigned char c : text) width += (c & 0xC0) != 0x80;
  return width;
}

namespace {

/// The first `width` code points of `text`, the last one "…" if it had to be cut.
std::string FitTo(const std::string& text, size_t width) {
  if (DisplayWidth(text) <= width) return text;
  if (width == 0) return {};
  std::string out;
  size_t points = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if ((c & 0xC0) != 0x80 && ++points == width) break;  // room for "…" only
    out += text[i];
  }
  return out + "…";
}

std::string Duration(double seconds) {
  if (seconds < 60.0) return fmt::format("{:.1f} s", seconds);
  if (seconds < 3600.0) return fmt::format("{}:{:02} min", static_cast<int>(seconds) / 60, static_cast<int>(seconds) % 60);
  return fmt::format("{:.1f} h", seconds / 3600.0);
}

}  // namespace

const char* MonitorState::Name(Condition condition) {
  switch (condition) {
    case Condition::kWaiting: return "WAITING";
    case Condition::kLocked: return "LOCKED";
    case Condition::kLost: return "LOST";
    case Condition::kHolding: return "HOLDING";
    case Condition::kNoSamples: return "NO SAMPLES";
  }
  return "?";
}

std::string MonitorState::TakeLine(double elapsed_s, int width) {
  clock_s_ += std::max(elapsed_s, 0.0);
  const double mean_error_deg = period_errors_ > 0 ? period_error_sum_deg_ / period_errors_ : NAN;
  Condition condition;
  if (have_state_ && !active_) {
    condition = Condition::kHolding;
  } else if (period_errors_ > 0) {
    condition = mean_error_deg < lock_threshold_deg_ ? Condition::kLocked : Condition::kLost;
  } else {
    condition = total_samples_ > 0 ? Condition::kNoSamples : Condition::kWaiting;
  }
  if (condition != condition_) {
    condition_ = condition;
    condition_since_s_ = clock_s_;
  }
  const std::string badge = condition == Condition::kWaiting
                                ? std::string(Name(condition))
                                : fmt::format("{} {}", Name(condition), Duration(clock_s_ - condition_since_s_));
  const double rate_hz = elapsed_s > 0 ? static_cast<double>(period_samples_) / elapsed_s : 0.0;
  std::string missed;
  for (const auto& [id, c] : controllers_) {
    missed += fmt::format("{}{}={}", missed.empty() ? "" : " ", id, c.missed_deadlines);
  }
  std::string line;
  if (width <= 0) {
    // The full line (logs, pipes): every field, always in the same order.
    std::string error;
    if (!target_) {
      error = target_problem_.empty() ? "error_deg - (no target yet)"
                                      : "error_deg - (invalid target: " + target_problem_ + ")";
    } else if (period_errors_ == 0) {
      error = "error_deg - (no samples)";
    } else {
      error = fmt::format("error_deg {:.3f} (max {:.3f})", mean_error_deg, period_error_max_deg_);
    }
    std::string driver;
    if (!have_state_) {
      driver = "driver - (no state yet)";
    } else if (active_) {
      driver = fmt::format("ACTIVE obeyed {} (priority {})", obeyed_id_.empty() ? "-" : obeyed_id_,
                           obeyed_priority_);
    } else {
      driver = fmt::format("HOLDING ({})", reason_.empty() ? "no reason given" : reason_);
    }
    line = fmt::format("{} | {} | phi {} | rate_hz {:.1f} | {} | missed_deadlines {} | target r{}", badge, error,
                       have_state_ ? FormatValues(phi_applied_.data(), phi_applied_.size(), 3) : "-", rate_hz,
                       driver, missed.empty() ? "-" : missed, RevisionCount(target_revision_));
  } else {
    // The terminal's line: the fields in order of importance; the least important dropped
    // until the line fits; the holding reason last, cut to the room left.
    struct Field {
      int drop_rank;  ///< higher: dropped earlier
      std::string text;
    };
    std::vector<Field> fields;
    fields.push_back({0, badge});
    if (!target_) {
      fields.push_back({1, target_problem_.empty() ? "no target yet" : "invalid target"});
    } else if (period_errors_ > 0) {
      fields.push_back({1, fmt::format("error {:.2f}° max {:.2f}°", mean_error_deg, period_error_max_deg_)});
    }
    if (have_state_ && active_) fields.push_back({2, fmt::format("obeys {} (p{})", obeyed_id_, obeyed_priority_)});
    fields.push_back({4, fmt::format("{:.0f} Hz", rate_hz)});
    if (have_state_) fields.push_back({5, "φ " + FormatValues(phi_applied_.data(), phi_applied_.size(), 3)});
    fields.push_back({6, fmt::format("target r{}", RevisionCount(target_revision_))});
    if (!missed.empty()) fields.push_back({7, "missed " + missed});
    const auto joined = [&] {
      std::string text;
      for (const auto& f : fields) text += (text.empty() ? "" : " | ") + f.text;
      return text;
    };
    const size_t limit = static_cast<size_t>(width);
    // Holding: the reason says why, so it keeps at least kMinReason characters.
    constexpr size_t kMinReason = 24;
    const bool holding = have_state_ && !active_;
    const size_t reserve = holding ? 3 + kMinReason : 0;
    line = joined();
    while (DisplayWidth(line) + reserve > limit && fields.size() > 1) {
      auto last = std::max_element(fields.begin(), fields.end(),
                                   [](const Field& a, const Field& b) { return a.drop_rank < b.drop_rank; });
      fields.erase(last);
      line = joined();
    }
    if (holding) {
      const std::string reason = reason_.empty() ? "no reason given" : reason_;
      const size_t used = DisplayWidth(line) + 3;
      if (used + 8 <= limit) line += " | " + FitTo(reason, limit - used);
    }
    line = FitTo(line, limit);
  }
  period_samples_ = 0;
  period_errors_ = 0;
  period_error_sum_deg_ = 0.0;
  period_error_max_deg_ = 0.0;
  return line;
}

// ---- the command

CLI::App* AddMonitorCommand(CLI::App& app, MonitorOptions* o) {
  CLI::App* monitor = app.add_subcommand(
      "monitor", "Live one-line status of a bench: error to target, phi, sample rate, driver mode");
  AddBusToolOptions(*monitor, &o->bus, "The bench to watch");
  monitor->add_option("--rate-hz", o->rate_hz, "Updates per second")
      ->check(cli::NumberIn(0.1, 100.0))
      ->capture_default_str();
  monitor->add_option("--lock-threshold-deg", o->lock_threshold_deg,
                      "LOCKED while the mean error of an update period is below this (degrees)")
      ->check(cli::NumberIn(0.0, 180.0))
      ->capture_default_str();
  monitor->add_option("--width", o->width,
                      "Fit the line to this many columns (default: the terminal's width when redrawing, "
                      "else the full line)")
      ->check(CLI::Range(20, 1000));
  monitor->add_flag("--lines", o->lines,
                    "One line per update instead of redrawing (the default when stdout is not a "
                    "terminal)");
  monitor->add_option("--duration-s", o->duration_s, "Stop after this long (0: until SIGINT/SIGTERM)")
      ->check(cli::NonNegativeNumber())
      ->capture_default_str();
  return monitor;
}

cli::ExitCode RunMonitorCommand(const MonitorOptions& o) {
  if (o.bus.bench_id.empty() || o.bus.bench_id == "*") {
    fmt::print(stderr, "dpc monitor: --bench-id: give one bench (\"{}\" would mix benches)\n",
               o.bus.bench_id);
    return cli::ExitCode::kInvalidInput;
  }
  StopSignals signals;
  const bool redraw = !o.lines && isatty(STDOUT_FILENO) == 1;
  try {
    std::mutex mutex;
    MonitorState state(o.lock_threshold_deg);
    ObserverParticipant participant(o.bus, "dpc monitor", "observer");
    const std::string& bench = o.bus.bench_id;
    std::unique_ptr<bus::Reader<msg::Target>> targets;
    std::unique_ptr<bus::Reader<msg::StokesSample>> samples;
    std::unique_ptr<bus::Reader<msg::WaveplateState>> states;
    std::unique_ptr<bus::Reader<msg::ControllerStatus>> statuses;
    // On the participant there is (again, after it healed a stalled handshake).
    const auto make_readers = [&] {
      targets = participant->MakeReader<msg::Target>(bench, [&](const msg::Target& m, const fdds::SampleInfo&) {
        std::lock_guard<std::mutex> lock(mutex);
        state.OnTarget(m);
      });
      samples = participant->MakeReader<msg::StokesSample>(
          bench, [&](const msg::StokesSample& m, const fdds::SampleInfo&) {
            std::lock_guard<std::mutex> lock(mutex);
            state.OnSample(m);
          });
      states = participant->MakeReader<msg::WaveplateState>(
          bench, [&](const msg::WaveplateState& m, const fdds::SampleInfo&) {
            std::lock_guard<std::mutex> lock(mutex);
            state.OnState(m);
          });
      statuses = participant->MakeReader<msg::ControllerStatus>(
          bench, [&](const msg::ControllerStatus& m, const fdds::SampleInfo&) {
            ControllerStatusReport checked;  // a status with figures no controller sends is not shown
            if (!bus::ReadStatus(m, &checked).empty()) return;
            std::lock_guard<std::mutex> lock(mutex);
            state.OnStatus(m);
          });
    };
    const auto delete_readers = [&] {
      statuses.reset();
      states.reset();
      samples.reset();
      targets.reset();
    };
    make_readers();
    fmt::print(stderr, "dpc monitor: domain {}, bench {}{}\n", o.bus.domain_id, bench,
               o.duration_s > 0 ? fmt::format(", {:g} s", o.duration_s) : ", Ctrl-C to stop");

    const auto start = Clock::now();
    const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / o.rate_hz));
    auto last = start;
    auto next = start + period;
    bool output_ok = true;
    while (output_ok) {
      while (Clock::now() < next && !StopSignals::requested()) {
        std::this_thread::sleep_for(std::min<Clock::duration>(next - Clock::now(), std::chrono::milliseconds(20)));
      }
      if (StopSignals::requested()) break;
      participant.Heal(delete_readers, make_readers);
      const auto now = Clock::now();
      std::string line;
      {
        std::lock_guard<std::mutex> lock(mutex);
        line = state.TakeLine(std::chrono::duration<double>(now - last).count(),
                              o.width > 0 ? o.width : redraw ? TerminalColumns() : 0);
      }
      last = now;
      next += period;
      if (next < now) next = now + period;  // we fell behind (suspended): do not burst
      if (redraw) {
        std::fputs(("\r" + line + "\x1b[K").c_str(), stdout);
      } else {
        std::fputs((line + "\n").c_str(), stdout);
      }
      output_ok = std::fflush(stdout) == 0;
      if (o.duration_s > 0 && std::chrono::duration<double>(now - start).count() >= o.duration_s) break;
    }
    if (redraw) std::fputs("\n", stdout);
    std::fflush(stdout);
    // Readers go before the participant (reverse declaration order); say why we stop.
    if (StopSignals::requested()) fmt::print(stderr, "dpc monitor: stopped by signal\n");
    return output_ok ? cli::ExitCode::kOk : cli::ExitCode::kRuntimeError;
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc monitor: {}\n", e.what());
    return cli::ExitCode::kRuntimeError;
  }
}

}  // namespace dpc::tools
