#include "target_command.h"

#include <fmt/format.h>
#include <unistd.h>

#include <mutex>
#include <optional>

#include "bus_messages.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/bench/clock.h"
#include "dpc/config/scenario_error.h"
#include "dpc/config/scenario_validation.h"
#include "dpc/cli/command_line.h"
#include "dpc/cli/exit_code.h"

namespace dpc::tools {
namespace {

namespace fdds = eprosima::fastdds::dds;

/// The flag that set the field at `location` ("target.point.s1" → "--point").
std::string FlagOf(const std::string& location, bool linear) {
  const auto starts = [&](std::string_view prefix) { return location.rfind(prefix, 0) == 0; };
  if (starts("target.point")) return "--point";
  if (starts("target.set.normal")) return linear ? "--linear" : "--set-normal";
  if (starts("target.set.offset")) return linear ? "--linear" : "--offset";
  return location;
}

std::string FreshRequestId() {
  return fmt::format("dpc-target-{}-{}", static_cast<long>(getpid()), WallClockNs());
}

}  // namespace

CLI::App* AddTargetCommand(CLI::App& app, TargetOptions* o) {
  CLI::App* target = app.add_subcommand(
      "target", "Ask the bench's driver to change the target (a point, or a set n·S = c)");
  AddBusToolOptions(*target, &o->bus, "The bench whose target changes");
  auto* point = target->add_option("--point", o->point, "Target point: a unit Stokes vector S1 S2 S3")
                    ->expected(3)
                    ->type_name("S1 S2 S3");
  auto* normal = target->add_option("--set-normal", o->normal,
                                    "Target set n·S = offset: the normal N1 N2 N3 (any non-zero length)")
                     ->expected(3)
                     ->type_name("N1 N2 N3");
  target->add_option("--offset", o->offset,
                                        "Offset c of the set n·S = c (|c|/|n| < 1; default 0)")
                         ->needs(normal);
  auto* linear = target->add_flag("--linear", o->linear,
                                  "Any linear polarization: the set [0, 0, 1]·S = 0");
  point->excludes(normal)->excludes(linear);
  normal->excludes(linear);
  target->add_option("--timeout-s", o->timeout_s, "How long to wait for the driver's reply")
      ->check(cli::NumberIn(0.1, 600.0))
      ->capture_default_str();
  return target;
}

TargetConfig LinearTarget() {
  TargetConfig target;
  target.kind = TargetConfig::Kind::kSet;
  target.normal = Vector3::UnitZ();
  target.offset = 0.0;
  return target;
}

std::optional<TargetConfig> CheckedTarget(TargetConfig target,
                                          const std::function<std::string(const std::string&)>& field_of,
                                          std::string* error) {
  try {
    ValidateTargetConfig(target);
  } catch (const ScenarioError& e) {
    *error = field_of(e.location()) + ": " + e.message();
    return std::nullopt;
  }
  return target;
}

std::optional<TargetConfig> TargetFromOptions(const TargetOptions& o, std::string* error) {
  TargetConfig target;
  if (!o.point.empty()) {
    if (o.point.size() != 3) {
      *error = "--point: give three numbers S1 S2 S3";
      return std::nullopt;
    }
    target.kind = TargetConfig::Kind::kPoint;
    target.point = StokesVector(o.point[0], o.point[1], o.point[2]);
  } else if (!o.normal.empty()) {
    if (o.normal.size() != 3) {
      *error = "--set-normal: give three numbers N1 N2 N3";
      return std::nullopt;
    }
    target.kind = TargetConfig::Kind::kSet;
    target.normal = Vector3(o.normal[0], o.normal[1], o.normal[2]);
    target.offset = o.offset;
  } else if (o.linear) {
    target = LinearTarget();
  } else {
    *error = "give the new target: --point S1 S2 S3, --set-normal N1 N2 N3 [--offset C], or --linear";
    return std::nullopt;
  }
  return CheckedTarget(target, [&](const std::string& location) { return FlagOf(location, o.linear); }, error);
}

cli::ExitCode RunTargetCommand(const TargetOptions& o) {
  std::string error;
  const std::optional<TargetConfig> target = TargetFromOptions(o, &error);
  if (!target) {
    fmt::print(stderr, "dpc target: {} (nothing sent)\n", error);
    return cli::ExitCode::kInvalidInput;
  }
  if (o.bus.bench_id.empty() || o.bus.bench_id == "*" || o.bus.bench_id.size() > 63) {
    fmt::print(stderr, "dpc target: --bench-id: \"{}\" is not a bench id (1 to 63 characters, "
                       "not \"*\": a target request goes to one bench)\n", o.bus.bench_id);
    return cli::ExitCode::kInvalidInput;
  }

  StopSignals signals;
  const std::string request_id = FreshRequestId();
  msg::TargetRequest request;
  request.bench_id(o.bus.bench_id);
  request.request_id(request_id);
  request.kind(target->kind == TargetConfig::Kind::kPoint ? msg::TARGET_POINT : msg::TARGET_SET);
  request.point(bus::ToArray(target->point));
  request.normal(bus::ToArray(target->normal));
  request.offset(target->offset);

  try {
    std::mutex mutex;
    std::optional<msg::TargetReply> reply;
    std::optional<msg::Target> applied;  // a dpc_target sample naming our request
    bus::BusParticipant participant(o.bus.Participant("dpc target", "operator"));
    // Readers before the request: the reply is VOLATILE, a reader created later misses it.
    auto replies = participant.MakeReader<msg::TargetReply>(
        o.bus.bench_id, [&](const msg::TargetReply& r, const fdds::SampleInfo&) {
          if (r.request_id().to_string() != request_id) return;
          std::lock_guard<std::mutex> lock(mutex);
          if (!reply) reply = r;
        });
    auto targets = participant.MakeReader<msg::Target>(
        o.bus.bench_id, [&](const msg::Target& t, const fdds::SampleInfo&) {
          if (t.request_id().to_string() != request_id) return;
          std::lock_guard<std::mutex> lock(mutex);
          if (!applied) applied = t;
        });
    auto writer = participant.MakeWriter<msg::TargetRequest>(o.bus.bench_id);

    const auto start = std::chrono::steady_clock::now();
    const bool matched = WaitFor(
        [&] { return writer->matched_readers() > 0 && replies->counters().matched_writers.load() > 0; },
        o.timeout_s);
    if (!matched) {
      if (StopSignals::requested()) return cli::ExitCode::kInterrupted;
      fmt::print(stderr,
                 "dpc target: no driver on domain {} within {:g} s ({}; is dpc-driver running "
                 "with this --domain?) — nothing sent\n",
                 o.bus.domain_id, o.timeout_s,
                 writer->matched_readers() == 0 ? "no reader of dpc_target_request matched"
                                                : "no writer of dpc_target_reply matched");
      return cli::ExitCode::kRuntimeError;
    }
    if (!writer->Write(request)) {
      fmt::print(stderr, "dpc target: Fast DDS refused to write the request\n");
      return cli::ExitCode::kRuntimeError;
    }
    const double remaining_s = std::max(0.1, o.timeout_s - SecondsSince(start));
    const bool answered = WaitFor(
        [&] {
          std::lock_guard<std::mutex> lock(mutex);
          return reply.has_value() || applied.has_value();
        },
        remaining_s);
    std::lock_guard<std::mutex> lock(mutex);
    if (!answered) {
      if (StopSignals::requested()) return cli::ExitCode::kInterrupted;
      fmt::print(stderr,
                 "dpc target: request {} sent, but no reply from the driver of bench {} on domain "
                 "{} within {:g} s (is the driver's --bench-id {}?)\n",
                 request_id, o.bus.bench_id, o.bus.domain_id, o.timeout_s, o.bus.bench_id);
      return cli::ExitCode::kRuntimeError;
    }
    if (reply && !reply->accepted()) {
      fmt::print(stderr, "dpc target: the driver refused request {}: {}\n", request_id,
                 reply->message().to_string());
      return cli::ExitCode::kInvalidInput;
    }
    const uint64_t revision = reply ? reply->revision() : applied->revision();
    const std::string shape = target->kind == TargetConfig::Kind::kPoint
                                  ? "point " + FormatValues(target->point.data(), 3)
                                  : fmt::format("set {}·S = {:.4f}",
                                                FormatValues(target->normal.data(), 3), target->offset);
    fmt::print("accepted: bench {} target revision {}: {} (request {})\n", o.bus.bench_id, revision,
               shape, request_id);
    return cli::ExitCode::kOk;
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc target: {}\n", e.what());
    return cli::ExitCode::kRuntimeError;
  }
}

}  // namespace dpc::tools
