#include "dashboard_command.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

#include "dashboard_model.h"
#include "dashboard_server.h"
#include "target_command.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/message_conversion.h"
#include "dpc/cli/command_line.h"

#ifndef DPC_DASHBOARD_BUILD_ASSETS
#define DPC_DASHBOARD_BUILD_ASSETS ""
#endif

namespace dpc::tools {
namespace {

namespace fdds = eprosima::fastdds::dds;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

constexpr double kRequestTimeoutS = 5.0;
constexpr size_t kMaxRequestsPerSecond = 4;

/// JSON text for the page; a string that is not valid UTF-8 (a peer's) is repaired, not thrown.
std::string Dump(const json& value) { return value.dump(-1, ' ', false, json::error_handler_t::replace); }

bool HasIndex(const std::string& dir) {
  std::error_code ec;
  return !dir.empty() && std::filesystem::is_regular_file(dir + "/index.html", ec);
}

/// What the server does with a page's messages: target requests, answered when the driver
/// answers (or does not).
class TargetRequests {
 public:
  explicit TargetRequests(const DashboardOptions& o) : options_(o) {}

  /// Before any message or reply arrives; `server` outlives the readers that call OnReply.
  void SetServer(DashboardServer* server) { server_ = server; }

  /// The writer of the requests from now on; a request being written is written first. Null:
  /// none, and the page's requests are refused with `refusal` (why there is none).
  void SetWriter(bus::Writer<msg::TargetRequest>* writer, std::string refusal = {}) {
    std::lock_guard<std::mutex> lock(writer_mutex_);
    writer_ = writer;
    refusal_ = std::move(refusal);
  }

  /// On the server's thread: a page's message.
  void OnPageMessage(uint64_t client, const std::string& text) {
    std::string tag;
    std::string error;
    const std::optional<TargetConfig> target = ParsePageTargetRequest(text, &tag, &error);
    if (!target) return Answer(client, tag, false, error, 0);
    std::lock_guard<std::mutex> writer_lock(writer_mutex_);
    if (writer_ == nullptr) return Answer(client, tag, false, refusal_, 0);
    const double now_s = Now();
    std::string request_id;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (const auto& [id, p] : pending_) {
        if (p.client == client) {
          return Answer(client, tag, false, "a request of this page is still waiting for the driver's answer", 0);
        }
      }
      while (!recent_s_.empty() && recent_s_.front() < now_s - 1.0) recent_s_.pop_front();
      if (recent_s_.size() >= kMaxRequestsPerSecond) {
        return Answer(client, tag, false, fmt::format("at most {} target requests a second", kMaxRequestsPerSecond), 0);
      }
      if (writer_->matched_readers() == 0) {
        return Answer(client, tag, false,
                      fmt::format("no driver listens for target requests on domain {} bench {} (is dpc-driver "
                                  "running?) — nothing sent",
                                  options_.bus.domain_id, options_.bus.bench_id), 0);
      }
      request_id = fmt::format("dpc-dashboard-{}-{}", static_cast<long>(getpid()), ++count_);
      pending_[request_id] = Pending{client, tag, now_s};
      recent_s_.push_back(now_s);
    }
    msg::TargetRequest request;
    request.bench_id(options_.bus.bench_id);
    request.request_id(request_id);
    request.kind(target->kind == TargetConfig::Kind::kPoint ? msg::TARGET_POINT : msg::TARGET_SET);
    request.point(bus::ToArray(target->point));
    request.normal(bus::ToArray(target->normal));
    request.offset(target->offset);
    if (!writer_->Write(request)) {
      Finish(request_id, false, "Fast DDS refused to write the request", 0);
    }
  }

  /// The driver's reply, or a target naming one of our requests.
  void OnReply(const std::string& request_id, bool accepted, const std::string& message, uint64_t revision) {
    Finish(request_id, accepted, message, revision);
  }

  /// Requests the driver never answered.
  void ExpireOld() {
    std::vector<std::string> expired;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (const auto& [id, p] : pending_) {
        if (Now() - p.sent_s > kRequestTimeoutS) expired.push_back(id);
      }
    }
    for (const auto& id : expired) {
      Finish(id, false, fmt::format("no answer from the driver within {:g} s", kRequestTimeoutS), 0);
    }
  }

 private:
  struct Pending {
    uint64_t client = 0;
    std::string tag;
    double sent_s = 0.0;
  };

  double Now() const { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

  void Finish(const std::string& request_id, bool accepted, const std::string& message, uint64_t revision) {
    Pending p;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      auto it = pending_.find(request_id);
      if (it == pending_.end()) return;  // not ours, or answered already
      p = it->second;
      pending_.erase(it);
    }
    Answer(p.client, p.tag, accepted, message, revision, request_id);
  }

  void Answer(uint64_t client, const std::string& tag, bool accepted, const std::string& message, uint64_t revision,
              const std::string& request_id = "") {
    json answer = {{"type", "target_reply"}, {"tag", tag}, {"accepted", accepted}, {"message", message}};
    if (!request_id.empty()) answer["request_id"] = request_id;
    if (accepted) {
      answer["revision"] = std::to_string(revision);  // beyond 2^53: text
      answer["revision_count"] = RevisionCount(revision);
    }
    if (server_ != nullptr) server_->Send(client, Dump(answer));
  }

  DashboardServer* server_ = nullptr;
  std::mutex writer_mutex_;  ///< before mutex_ where both are held
  bus::Writer<msg::TargetRequest>* writer_ = nullptr;  ///< SetWriter
  std::string refusal_ = "no DDS writer of target requests yet";  ///< SetWriter, while writer_ is null
  const DashboardOptions& options_;
  std::mutex mutex_;
  std::map<std::string, Pending> pending_;
  std::deque<double> recent_s_;
  uint64_t count_ = 0;
};

}  // namespace

std::string DefaultDashboardAssets() {
  if (const char* env = std::getenv("DPC_DASHBOARD_ASSETS"); env != nullptr && *env != '\0') return env;
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const std::string installed = (exe.parent_path().parent_path() / "share" / "dpc" / "dashboard").string();
    if (HasIndex(installed)) return installed;
  }
  if (HasIndex(DPC_DASHBOARD_BUILD_ASSETS)) return DPC_DASHBOARD_BUILD_ASSETS;
  return "";
}

std::optional<TargetConfig> ParsePageTargetRequest(const std::string& text, std::string* tag, std::string* error) {
  const json message = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (message.is_discarded() || !message.is_object()) {
    *error = "not a JSON object";
    return std::nullopt;
  }
  if (auto it = message.find("tag"); it != message.end() && it->is_string()) {
    *tag = bus::PrintableName(it->get<std::string>());
  }
  auto type = message.find("type");
  if (type == message.end() || !type->is_string() || type->get<std::string>() != "set_target") {
    *error = "unknown request (the dashboard takes {\"type\": \"set_target\", …})";
    return std::nullopt;
  }
  const auto triple = [&](const char* name, Vector3* out) {
    auto it = message.find(name);
    if (it == message.end() || !it->is_array() || it->size() != 3) {
      *error = fmt::format("{}: give three numbers", name);
      return false;
    }
    for (size_t i = 0; i < 3; ++i) {
      if (!(*it)[i].is_number()) {
        *error = fmt::format("{}: give three numbers", name);
        return false;
      }
      (*out)[static_cast<Eigen::Index>(i)] = (*it)[i].get<double>();
    }
    return true;
  };
  auto kind = message.find("kind");
  const std::string k = kind != message.end() && kind->is_string() ? kind->get<std::string>() : "";
  TargetConfig target;
  if (k == "point") {
    target.kind = TargetConfig::Kind::kPoint;
    Vector3 point;
    if (!triple("point", &point)) return std::nullopt;
    target.point = point;
  } else if (k == "set") {
    target.kind = TargetConfig::Kind::kSet;
    if (!triple("normal", &target.normal)) return std::nullopt;
    auto offset = message.find("offset");
    if (offset != message.end()) {
      if (!offset->is_number()) {
        *error = "offset: give a number";
        return std::nullopt;
      }
      target.offset = offset->get<double>();
    }
  } else if (k == "linear") {
    target = LinearTarget();
  } else {
    *error = "kind: give \"point\", \"set\" or \"linear\"";
    return std::nullopt;
  }
  // The page's field names are the scenario's without "target." ("point.s1", "set.normal").
  return CheckedTarget(
      target,
      [](const std::string& location) { return location.rfind("target.", 0) == 0 ? location.substr(7) : location; },
      error);
}

CLI::App* AddDashboardCommand(CLI::App& app, DashboardOptions* o) {
  CLI::App* dashboard = app.add_subcommand(
      "dashboard", "Live web view of a bench: Poincaré sphere, error, phi, driver and controllers; set the target");
  AddBusToolOptions(*dashboard, &o->bus, "The bench to show");
  dashboard->add_option("--port", o->port, "TCP port of the page (0: any free port; the URL is printed)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  dashboard->add_option("--bind", o->bind_address,
                        "Address to listen on (127.0.0.1: this host only; another address exposes the page "
                        "and its target control to that network)")
      ->capture_default_str();
  dashboard->add_option("--push-hz", o->push_hz, "Snapshots pushed to the page per second")
      ->check(cli::NumberIn(1.0, 60.0))
      ->capture_default_str();
  dashboard->add_option("--lock-threshold-deg", o->lock_threshold_deg,
                        "LOCKED while the mean error of a push period is below this (degrees)")
      ->check(cli::NumberIn(0.0, 180.0))
      ->capture_default_str();
  dashboard->add_option("--assets", o->assets_dir,
                        "Directory of the page's files (default: $DPC_DASHBOARD_ASSETS, the installed "
                        "share/dpc/dashboard, or the build tree's)");
  dashboard->add_option("--duration-s", o->duration_s, "Stop after this long (0: until SIGINT/SIGTERM)")
      ->check(cli::NonNegativeNumber())
      ->capture_default_str();
  AddStuckExitOption(*dashboard, &o->stuck_exit_s, " (a supervisor then starts it again)");
  return dashboard;
}

cli::ExitCode RunDashboardCommand(const DashboardOptions& o) {
  if (o.bus.bench_id.empty() || o.bus.bench_id == "*") {
    fmt::print(stderr, "dpc dashboard: --bench-id: give one bench (\"{}\" would mix benches)\n", o.bus.bench_id);
    return cli::ExitCode::kInvalidInput;
  }
  const std::string assets = o.assets_dir.empty() ? DefaultDashboardAssets() : o.assets_dir;
  if (!HasIndex(assets)) {
    fmt::print(stderr,
               "dpc dashboard: the page's files were not found{} (build the dpc_dashboard_assets target, "
               "which copies three.js and uPlot from npm, or give --assets DIR)\n",
               assets.empty() ? "" : fmt::format(" in {}", assets));
    return cli::ExitCode::kInitializationError;
  }
  StopSignals signals;
  // Made first: it also guards the end (the participant and the web server deleted).
  const std::unique_ptr<cli::LoopGuard> guard = GuardCommandLoop("dashboard", o.stuck_exit_s);
  guard->Phase("its start");
  try {
    std::mutex mutex;
    const auto start = Clock::now();
    const auto now_s = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
    DashboardModel model(DashboardModelOptions{o.lock_threshold_deg});
    ObserverParticipant participant(o.bus, "dpc dashboard", "operator");
    participant.SetPhaseReport([&guard](const char* phase) { return guard->Phase(phase); });
    const std::string& bench = o.bus.bench_id;

    // The writer before `requests` and the server: it goes after them (reverse order), so no
    // page's request is written through a writer that is gone.
    std::unique_ptr<bus::Writer<msg::TargetRequest>> request_writer;
    TargetRequests requests(o);
    // The server before the readers: they go first, so no callback answers through a server
    // that is gone.
    DashboardServer web(DashboardServerOptions{o.bind_address, o.port, assets},
                        [&](uint64_t client, const std::string& text) { requests.OnPageMessage(client, text); });
    requests.SetServer(&web);

    BenchSummary summary;
    std::unique_ptr<bus::Reader<msg::TargetReply>> replies;
    std::unique_ptr<bus::Reader<msg::Target>> targets;
    std::unique_ptr<bus::Reader<msg::DeviceDescription>> devices;
    std::unique_ptr<bus::Reader<msg::BenchSummary>> summaries;
    std::unique_ptr<bus::Reader<msg::ControllerStatus>> statuses;
    // On the participant there is (again, after it healed a stalled handshake).
    const auto make_endpoints = [&] {
      try {
        request_writer = participant->MakeWriter<msg::TargetRequest>(bench);
      } catch (const std::exception& e) {
        fmt::print(stderr, "dpc dashboard: read-only, the page cannot set the target: {}\n", e.what());
      }
      requests.SetWriter(request_writer.get(),
                         "this dashboard may not publish target requests (its DDS identity has no such permission: "
                         "give --identity operator)");
      replies = participant->MakeReader<msg::TargetReply>(bench, [&](const msg::TargetReply& r, const fdds::SampleInfo&) {
        requests.OnReply(r.request_id().to_string(), r.accepted(), r.message().to_string(), r.revision());
      });
      targets = participant->MakeReader<msg::Target>(bench, [&](const msg::Target& m, const fdds::SampleInfo&) {
        BenchTarget read;
        std::string problem = bus::ReadTarget(m, &read);
        std::lock_guard<std::mutex> lock(mutex);
        if (!problem.empty()) return model.OnRefused("dpc_target", problem);
        model.OnTarget(read);
        if (!read.request_id.empty()) requests.OnReply(read.request_id, true, "", read.revision);
      });
      devices = participant->MakeReader<msg::DeviceDescription>(
          bench, [&](const msg::DeviceDescription& m, const fdds::SampleInfo&) {
            DeviceDescription read;
            std::string problem = bus::ReadDevice(m, &read);
            std::lock_guard<std::mutex> lock(mutex);
            if (!problem.empty()) return model.OnRefused("dpc_device_description", problem);
            model.OnDevice(read);
          });
      // The bench through the polarimeter's summaries, never at its own rate.
      summaries = participant->MakeReader<msg::BenchSummary>(
          bench, [&](const msg::BenchSummary& m, const fdds::SampleInfo&) {
            std::lock_guard<std::mutex> lock(mutex);
            std::string problem = bus::ReadSummary(m, &summary);
            if (!problem.empty()) return model.OnRefused("dpc_bench_summary", problem);
            model.OnSummary(summary, now_s());
          });
      statuses = participant->MakeReader<msg::ControllerStatus>(
          bench, [&](const msg::ControllerStatus& m, const fdds::SampleInfo&) {
            ControllerStatusReport report;
            std::string problem = bus::ReadStatus(m, &report);
            std::lock_guard<std::mutex> lock(mutex);
            if (!problem.empty()) return model.OnRefused("dpc_controller_status", problem);
            model.OnStatus(report, now_s());
          });
    };
    const auto delete_endpoints = [&] {
      requests.SetWriter(nullptr,
                         "this dashboard is making its DDS participant again (a security handshake had stalled): "
                         "send the target again in a second");
      statuses.reset();
      summaries.reset();
      devices.reset();
      targets.reset();
      replies.reset();
      request_writer.reset();
    };
    make_endpoints();

    const std::string host = o.bind_address.find(':') != std::string::npos ? "[" + o.bind_address + "]" : o.bind_address;
    fmt::print("dpc dashboard: http://{}:{}/\n", host == "0.0.0.0" ? "127.0.0.1" : host, web.port());
    std::fflush(stdout);
    fmt::print(stderr, "dpc dashboard: domain {}, bench {}, page files {}{}\n", o.bus.domain_id, bench, assets,
               o.duration_s > 0 ? fmt::format(", {:g} s", o.duration_s) : ", Ctrl-C to stop");

    const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / o.push_hz));
    auto next = start + period;
    guard->Phase("its pushes");
    while (!StopSignals::requested()) {
      while (Clock::now() < next && !StopSignals::requested()) {
        guard->Turn();
        std::this_thread::sleep_for(std::min<Clock::duration>(next - Clock::now(), std::chrono::milliseconds(20)));
      }
      if (StopSignals::requested()) break;
      participant.Heal(delete_endpoints, make_endpoints);
      next += period;
      if (next < Clock::now()) next = Clock::now() + period;  // fell behind: do not burst
      json snapshot;
      {
        std::lock_guard<std::mutex> lock(mutex);
        snapshot = model.TakeSnapshot(now_s());
      }
      snapshot["bench_id"] = bench;
      snapshot["domain"] = o.bus.domain_id;
      snapshot["push_hz"] = o.push_hz;
      snapshot["read_only"] = request_writer == nullptr;
      snapshot["pages"] = web.clients();
      web.Broadcast(Dump(snapshot));
      requests.ExpireOld();
      if (o.duration_s > 0 && now_s() >= o.duration_s) break;
    }
    guard->Phase("the deletion of its DDS entities and its web server");
    guard->Stopping();
    if (StopSignals::requested()) fmt::print(stderr, "dpc dashboard: stopped by signal\n");
    return cli::ExitCode::kOk;
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc dashboard: {}\n", e.what());
    return cli::ExitCode::kInitializationError;
  }
}

}  // namespace dpc::tools
