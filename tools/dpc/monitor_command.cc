#include "monitor_command.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <mutex>
#include <numbers>
#include <thread>

#include "bus_messages.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/config/scenario_builders.h"
#include "dpc/cli/exit_code.h"

namespace dpc::tools {
namespace {

namespace fdds = eprosima::fastdds::dds;
using Clock = std::chrono::steady_clock;

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

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

std::string MonitorState::TakeLine(double elapsed_s) {
  std::string error;
  if (!target_) {
    error = target_problem_.empty() ? "error_deg - (no target yet)"
                                    : "error_deg - (invalid target: " + target_problem_ + ")";
  } else if (period_errors_ == 0) {
    error = "error_deg - (no samples)";
  } else {
    error = fmt::format("error_deg {:.3f} (max {:.3f})", period_error_sum_deg_ / period_errors_,
                        period_error_max_deg_);
  }
  const double rate_hz = elapsed_s > 0 ? static_cast<double>(period_samples_) / elapsed_s : 0.0;
  std::string driver;
  if (!have_state_) {
    driver = "driver - (no state yet)";
  } else if (active_) {
    driver = fmt::format("ACTIVE obeyed {} (priority {})", obeyed_id_.empty() ? "-" : obeyed_id_,
                         obeyed_priority_);
  } else {
    driver = fmt::format("HOLDING ({})", reason_.empty() ? "no reason given" : reason_);
  }
  std::string missed;
  for (const auto& [id, c] : controllers_) {
    missed += fmt::format("{}{}={}", missed.empty() ? "" : " ", id, c.missed_deadlines);
  }
  std::string line = fmt::format(
      "{} | phi {} | rate_hz {:.1f} | {} | missed_deadlines {} | target r{}", error,
      have_state_ ? FormatValues(phi_applied_.data(), phi_applied_.size(), 3) : "-", rate_hz, driver,
      missed.empty() ? "-" : missed, RevisionCount(target_revision_));
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
      ->check(CLI::Range(0.1, 100.0))
      ->capture_default_str();
  monitor->add_flag("--lines", o->lines,
                    "One line per update instead of redrawing (the default when stdout is not a "
                    "terminal)");
  monitor->add_option("--duration-s", o->duration_s, "Stop after this long (0: until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber)
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
    MonitorState state;
    bus::BusParticipant participant(o.bus.Participant("dpc monitor", "observer"));
    const std::string& bench = o.bus.bench_id;
    auto targets = participant.MakeReader<msg::Target>(bench, [&](const msg::Target& m, const fdds::SampleInfo&) {
      std::lock_guard<std::mutex> lock(mutex);
      state.OnTarget(m);
    });
    auto samples = participant.MakeReader<msg::StokesSample>(
        bench, [&](const msg::StokesSample& m, const fdds::SampleInfo&) {
          std::lock_guard<std::mutex> lock(mutex);
          state.OnSample(m);
        });
    auto states = participant.MakeReader<msg::WaveplateState>(
        bench, [&](const msg::WaveplateState& m, const fdds::SampleInfo&) {
          std::lock_guard<std::mutex> lock(mutex);
          state.OnState(m);
        });
    auto statuses = participant.MakeReader<msg::ControllerStatus>(
        bench, [&](const msg::ControllerStatus& m, const fdds::SampleInfo&) {
          std::lock_guard<std::mutex> lock(mutex);
          state.OnStatus(m);
        });
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
      const auto now = Clock::now();
      std::string line;
      {
        std::lock_guard<std::mutex> lock(mutex);
        line = state.TakeLine(std::chrono::duration<double>(now - last).count());
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
