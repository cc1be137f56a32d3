#pragma once
// The fixture of the tests that run the bench as real processes on loopback: it starts
// dpc-driver, dpc-controller(s) and dpc-polarimeter on the test's own DDS domain (each logging
// to a file), watches the bus through its own participant (states, samples, controller status),
// and ends every process it started (SIGINT, then SIGKILL) when the test ends.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dpc/bench/clock.h"
#include "dpc/bus/bus_participant.h"
#include "dpc/bus/handshake_watchdog.h"
#include "support/process.h"
#include "support/test_directory.h"

namespace dpc::testing {

/// The running test's own directory: never one an earlier test left, whose driver record would
/// start this test's driver "where the waveplates were left" by another test.
inline std::string BenchTempDir() { return FreshTestDirectory("dpc_bench").string(); }

/// One applied state as seen by the test.
struct SeenState {
  msg::WaveplateState state;
  int64_t seen_ns;
};

/// A failover as the states show it: the last state applying `from`'s command and the first
/// after it applying `to`'s (standing in, or obeyed), by index and publish time (when applied).
struct Handover {
  size_t last_from = 0, first_to = 0;
  int64_t last_from_ns = 0, first_to_ns = 0;
};

/// The handover from `from` to `to` in `states`, or nullopt if `to` applied nothing after
/// `from`'s last state. (A loaded machine may have handed over briefly before: only what
/// follows `from`'s last state counts; the driver's own switch notice repeats `from`'s last
/// command and is skipped.)
inline std::optional<Handover> FindHandover(const std::vector<SeenState>& states, const std::string& from,
                                            const std::string& to) {
  Handover h;
  for (size_t i = 0; i < states.size(); ++i) {
    const auto& s = states[i].state;
    if (s.answers_sample() > 0 && s.applied_controller_id().to_string() == from) {
      h.last_from = i;
      h.last_from_ns = s.publish_time_ns();
    }
  }
  for (size_t i = h.last_from + 1; i < states.size(); ++i) {
    const auto& s = states[i].state;
    if (s.answers_sample() > 0 && s.applied_controller_id().to_string() == to && s.publish_time_ns() > h.last_from_ns) {
      h.first_to = i;
      h.first_to_ns = s.publish_time_ns();
      return h;
    }
  }
  return std::nullopt;
}

class BenchFixture : public ::testing::Test {
 protected:
  /// The test's own participant on `domain` (with `security`: DDS Security credentials, e.g.
  /// the observer identity of a secure bench).
  void StartObserver(int domain, bus::SecurityOptions security = {}) {
    domain_ = domain;
    observer_security_ = security;
    participant_ =
        std::make_unique<bus::BusParticipant>(bus::BusOptions{domain, "dpc-test-observer", std::move(security)});
    states_ = participant_->MakeReader<msg::WaveplateState>(
        "bench1", [this](const msg::WaveplateState& state, const auto&) {
          std::lock_guard<std::mutex> lock(mutex_);
          seen_.push_back({state, MonotonicNs()});
        });
    samples_ = participant_->MakeReader<msg::StokesSample>(
        "bench1", [this](const msg::StokesSample& sample, const auto&) {
          // Error of the measured output to the default target [0, 0.6, 0.8], degrees.
          const auto& s = sample.s_out();
          const double cosine = std::clamp(0.6 * s[1] + 0.8 * s[2], -1.0, 1.0);
          std::lock_guard<std::mutex> lock(mutex_);
          sample_errors_.push_back({sample.publish_time_ns(), std::acos(cosine) * 180.0 / M_PI});
        });
    statuses_ = participant_->MakeReader<msg::ControllerStatus>(
        "bench1", [this](const msg::ControllerStatus& status, const auto&) {
          std::lock_guard<std::mutex> lock(mutex_);
          statuses_seen_[status.controller_id().to_string()] = status;
        });
  }
  /// The test's participant made again with `security` (e.g. rotated credentials); what it saw
  /// so far is kept.
  void RestartObserver(bus::SecurityOptions security = {}) {
    statuses_.reset();
    samples_.reset();
    states_.reset();
    participant_.reset();
    StartObserver(domain_, std::move(security));
  }
  /// Fast DDS 2.9's security handshake can stall for good (bus/handshake_watchdog.h). A service
  /// heals only the stalls that cost it progress, so one with the test's observer lasts: the
  /// observer heals its own, as a `dpc` observer does, by making its participant again when a
  /// handshake has been pending for HandshakeWatchdog::kStallNs, and says so. Whether it did.
  bool HealObserverStall() {
    if (!participant_) return false;
    const std::vector<std::string> stalled = participant_->PendingHandshakes(bus::HandshakeWatchdog::kStallNs);
    if (stalled.empty()) return false;
    std::fprintf(stderr, "note: the observer's handshake with %s stalled (Fast DDS 2.9); a new participant\n",
                 bus::NamedPeers(stalled).c_str());
    RestartObserver(observer_security_);
    return true;
  }
  void TearDown() override {
    processes_.clear();  // ends them (SIGINT, then SIGKILL)
    statuses_.reset();
    samples_.reset();
    states_.reset();
    participant_.reset();
    // A failed test's logs, traces and device record stay for a look.
    if (!HasFailure()) {
      std::error_code ignored;
      std::filesystem::remove_all(dir_, ignored);
    }
  }

  Process& Start(const std::string& binary, std::vector<std::string> args, const std::string& name) {
    args.insert(args.begin(), binary);
    args.push_back("--domain");
    args.push_back(std::to_string(domain_));
    args.insert(args.end(), common_args_.begin(), common_args_.end());
    processes_.push_back(std::make_unique<Process>(args, dir_ + "/" + name + ".log"));
    return *processes_.back();
  }
  /// The driver, its device record (where the waveplates are, across its restarts) in the
  /// test's directory.
  Process& StartDriver(std::vector<std::string> args = {}, const std::string& name = "driver") {
    args.insert(args.end(), {"--device-record", dir_ + "/driver.record"});
    return Start(DPC_DRIVER_BINARY, std::move(args), name);
  }
  Process& StartController(const std::string& id, int priority, std::vector<std::string> args = {}) {
    args.insert(args.end(), {"--id", id, "--priority", std::to_string(priority)});
    return Start(DPC_CONTROLLER_BINARY, std::move(args), "controller_" + id);
  }
  Process& StartPolarimeter(std::vector<std::string> args, const std::string& name = "polarimeter") {
    return Start(DPC_POLARIMETER_BINARY, std::move(args), name);
  }

  std::vector<SeenState> States() {
    std::lock_guard<std::mutex> lock(mutex_);
    return seen_;
  }
  size_t StateCount() {
    std::lock_guard<std::mutex> lock(mutex_);
    return seen_.size();
  }
  std::optional<msg::WaveplateState> LatestState() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (seen_.empty()) return std::nullopt;
    return seen_.back().state;
  }
  std::optional<msg::ControllerStatus> Status(const std::string& id) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = statuses_seen_.find(id);
    if (it == statuses_seen_.end()) return std::nullopt;
    return it->second;
  }
  bool Obeys(const std::string& id) {
    auto state = LatestState();
    return state && state->mode() == msg::DRIVER_ACTIVE && state->obeyed_controller_id().to_string() == id;
  }
  /// Obeys(id) within `timeout`: the latest state may be a holding heartbeat of a stall of the
  /// whole machine, after which the driver gives control back to the same controller.
  bool SoonObeys(const std::string& id, std::chrono::milliseconds timeout = std::chrono::seconds(2)) {
    return Eventually([&] { return Obeys(id); }, timeout);
  }
  /// The largest output error of the samples published in [from_ns, to_ns] (wall clock).
  double MaxErrorDeg(int64_t from_ns, int64_t to_ns) {
    const std::vector<double> errors = ErrorsDeg(from_ns, to_ns);
    return errors.empty() ? 0.0 : *std::max_element(errors.begin(), errors.end());
  }
  /// The median output error of the samples published in [from_ns, to_ns] (wall clock); NaN if
  /// none. Unlike the largest, a stall of the whole machine does not move it.
  double MedianErrorDeg(int64_t from_ns, int64_t to_ns) {
    std::vector<double> errors = ErrorsDeg(from_ns, to_ns);
    if (errors.empty()) return NAN;
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    return errors[errors.size() / 2];
  }
  /// (publish time, output error) of the samples published in [from_ns, to_ns] (wall clock).
  std::vector<std::pair<int64_t, double>> ErrorsWithTimes(int64_t from_ns, int64_t to_ns) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::pair<int64_t, double>> out;
    for (const auto& [t, e] : sample_errors_) {
      if (t >= from_ns && t <= to_ns) out.emplace_back(t, e);
    }
    return out;
  }
  /// The output errors of the samples published in [from_ns, to_ns] (wall clock).
  std::vector<double> ErrorsDeg(int64_t from_ns, int64_t to_ns) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<double> errors;
    for (const auto& [t, e] : sample_errors_) {
      if (t >= from_ns && t <= to_ns) errors.push_back(e);
    }
    return errors;
  }
  /// Applied states obeying `id` seen so far.
  /// States that applied a command of `id` (obeyed, or standing in).
  size_t AppliedBy(const std::string& id) {
    std::lock_guard<std::mutex> lock(mutex_);
    size_t n = 0;
    for (const auto& s : seen_) n += s.state.applied_controller_id().to_string() == id && s.state.answers_sample() > 0;
    return n;
  }

  std::string Logs() {
    std::string all;
    for (auto& p : processes_) all += "---- " + p->out_path().string() + "\n" + p->Log();
    return all;
  }

  std::string dir_ = BenchTempDir();
  int domain_ = 0;
  std::vector<std::string> common_args_;  ///< given to every service started (e.g. --security-dir)
  std::unique_ptr<bus::BusParticipant> participant_;
  std::unique_ptr<bus::Reader<msg::WaveplateState>> states_;
  std::unique_ptr<bus::Reader<msg::ControllerStatus>> statuses_;
  std::unique_ptr<bus::Reader<msg::StokesSample>> samples_;
  std::vector<std::pair<int64_t, double>> sample_errors_;  ///< (publish time ns, error deg)
  std::mutex mutex_;
  std::vector<SeenState> seen_;
  std::map<std::string, msg::ControllerStatus> statuses_seen_;
  std::vector<std::unique_ptr<Process>> processes_;
  bus::SecurityOptions observer_security_;
};

}  // namespace dpc::testing
