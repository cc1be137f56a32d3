// dpc-emulator: the instruments a lab attaches to the bench — an electronic polarization
// controller (EPC, voltages per channel) and a polarimeter (S_in, S_out) — emulated on a
// scenario's true device and served over TCP on 127.0.0.1 (and pseudo-terminals with --pty),
// with a control port that injects faults. One thread around ppoll: the optics advance by the
// monotonic clock at every event and at least every millisecond.
//
//   dpc-emulator [SCENARIO] [--tcp-port-epc 5025] [--tcp-port-polarimeter 5026]
//                [--control-port 5027] [--pty] [--dac-bits 16] [--latency-s 0] …
//
// At start-up it prints one JSON line on stdout with the ports (and the pseudo-terminals'
// paths), e.g. {"epc_tcp":5025,"polarimeter_tcp":5026,"control_tcp":5027}.

#include <poll.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "dpc/bench/clock.h"
#include "emulator_core.h"
#include "emulator_io.h"
#include "log_limiter.h"
#include "service.h"

namespace dpc::services {

/// deploy/scenarios/emulator_epc.pbtxt, compiled in (emulator_default_scenario.cc.in).
const char* DefaultEmulatorScenarioText();

namespace {

/// Bytes read from one client per wake-up: a client sending without pause cannot starve the
/// others.
constexpr size_t kReadChunkBytes = 4096;
/// Connections taken from one listener per wake-up.
constexpr int kAcceptsPerWakeup = 16;
/// The optics advance at least this often, events or not.
constexpr int64_t kMaxIdleNs = 1'000'000;

struct EmulatorOptions {
  EmulatorSettings settings;
  int epc_port = 5025;          // 5025: the usual port of SCPI instruments' raw sockets
  int polarimeter_port = 5026;
  int control_port = 5027;
  bool pty = false;
};

EmulatorCore MakeCore(const CommonOptions& common, const EmulatorOptions& options, EmulatorCore::EventSink sink) {
  try {
    ValidateEmulatorSettings(options.settings);
  } catch (const std::invalid_argument& e) {
    throw ConfigurationError(e.what());
  }
  const ScenarioConfig scenario =
      LoadServiceScenario(common, DefaultEmulatorScenarioText(), "<emulator_epc.pbtxt>");
  return EmulatorCore(scenario, options.settings, MonotonicNs(), std::move(sink));  // ScenarioError
}

class EmulatorService final : public Service {
 public:
  using Options = EmulatorOptions;

  static void AddOptions(CLI::App& app, Options* o) {
    // The emulator speaks no DDS: the skeleton's DDS options would be taken and ignored.
    for (const char* dds : {"--domain", "--security-dir", "--identity"}) app.remove_option(app.get_option(dds));
    app.get_option("--bench-id")->description("A label for the log lines (the emulator publishes nothing)");
    app.get_option("--stuck-exit-s")
        ->description("Exit with code 1, saying where, when the emulator's loop has not turned for this long (a "
                      "call that never returns), so that a supervisor restarts it; raised to what the emulator's "
                      "own timeouts need. 0: never");
    app.get_option("SCENARIO")
        ->description("Scenario file of the TRUE device (text format, common/proto/dpc/scenario.proto): its stages "
                      "and maps with φ = the channel's voltage in volts, its input SOP (stepped at "
                      "simulation.sample_rate_hz on the wall clock), simulation.polarimeter_noise_deg (--noise-deg) "
                      "and simulation.seed (--seed); default: the embedded deploy/scenarios/emulator_epc.pbtxt");
    const auto port = [&](const char* name, int* value, const char* what) {
      app.add_option(name, *value, fmt::format("TCP port of {} on 127.0.0.1 (0: a free one, printed)", what))
          ->check(CLI::Range(0, 65535))
          ->capture_default_str();
    };
    port("--tcp-port-epc", &o->epc_port, "the EPC");
    port("--tcp-port-polarimeter", &o->polarimeter_port, "the polarimeter");
    port("--control-port", &o->control_port, "the control port (faults, temperature, status)");
    app.add_flag("--pty", o->pty,
                 "Also serve both instruments on pseudo-terminals (raw mode; their paths are printed): a client "
                 "opens one as a serial port");
    EmulatorSettings& s = o->settings;
    app.add_option("--dac-bits", s.dac_bits, "The EPC's DAC: voltages are quantized to 2^bits codes over the full scale")
        ->capture_default_str();
    app.add_option("--volts-min", s.volts_min, "The DAC's full scale, lower end (V); a voltage outside is refused")
        ->capture_default_str();
    app.add_option("--volts-max", s.volts_max, "The DAC's full scale, upper end (V)")->capture_default_str();
    app.add_option("--settling-s", s.settling_s,
                   "Time constant of each channel's first-order settling to its set voltage (0: at once)")
        ->capture_default_str();
    app.add_option("--hysteresis-v", s.hysteresis_v,
                   "Half-width of the play (backlash) between each channel's set and effective voltage (V)")
        ->capture_default_str();
    app.add_option("--temperature-c", s.temperature_c,
                   "The device's temperature: every retardance is θ(V)·(1 + k·(T − 25 °C)), the scenario's maps "
                   "being the truth at 25 °C (the control port's `temperature` changes it)")
        ->capture_default_str();
    app.add_option("--temperature-coefficient-per-k", s.temperature_coefficient_per_k,
                   "k: the retardance's relative change per kelvin")
        ->capture_default_str();
    app.add_option("--wavelength-nm", s.wavelength_nm,
                   "The light's wavelength: every retardance is θ(V)·1550 nm/λ, the scenario's maps being the truth at "
                   "1550 nm (the control port's `wavelength` changes it)")
        ->capture_default_str();
    app.add_option("--latency-s", s.latency_s, "Every reply leaves this long after its query")->capture_default_str();
  }
  static std::string LogName(const Options&) { return "emulator"; }

  EmulatorService(const CommonOptions& common, const Options& options)
      : core_(MakeCore(common, options, [this](const std::string& kind, const std::string& text) { Log(kind, text); })) {
    struct Port {
      Instrument instrument;
      int port;
      const char* option;
    };
    for (const Port& p : {Port{Instrument::kEpc, options.epc_port, "--tcp-port-epc"},
                          Port{Instrument::kPolarimeter, options.polarimeter_port, "--tcp-port-polarimeter"},
                          Port{Instrument::kControl, options.control_port, "--control-port"}}) {
      FileDescriptor socket = ListenOnLoopback(p.port, p.option);
      const int bound = BoundPort(socket.get());
      listeners_.push_back(Listener{p.instrument, std::move(socket), bound});
    }
    if (options.pty) {
      for (Instrument instrument : {Instrument::kEpc, Instrument::kPolarimeter}) {
        ptys_.push_back(std::make_unique<PtyEndpoint>(PtyEndpoint{instrument, PseudoTerminal(), std::nullopt}));
      }
    }
    const EmulatedDevice& device = core_.device();
    spdlog::info("EPC: {} channels ({}), DAC {} bits over [{:g}, {:g}] V (step {:.4g} mV), settling {:g} s, "
                 "hysteresis {:g} V, {:g} °C (k = {:g}/K), {:g} nm, latency {:g} s",
                 device.channel_count(), device.chain().Describe(), options.settings.dac_bits,
                 options.settings.volts_min, options.settings.volts_max, device.dac().step_v() * 1e3,
                 options.settings.settling_s, options.settings.hysteresis_v, options.settings.temperature_c,
                 options.settings.temperature_coefficient_per_k, options.settings.wavelength_nm,
                 options.settings.latency_s);
    for (const Listener& l : listeners_) spdlog::info("{} on 127.0.0.1:{}", InstrumentName(l.instrument), l.port);
    for (const auto& p : ptys_) spdlog::info("{} on {}", InstrumentName(p->instrument), p->terminal.path());
  }

  /// A turn polls for at most kMaxIdleNs; the instruments' sockets and terminals never block.
  std::optional<double> LongestTurnS() const override { return 0.0; }

  cli::ExitCode run() override {
    nlohmann::ordered_json ready;
    ready["epc_tcp"] = listeners_[0].port;
    ready["polarimeter_tcp"] = listeners_[1].port;
    ready["control_tcp"] = listeners_[2].port;
    for (const auto& p : ptys_) ready[fmt::format("{}_pty", InstrumentName(p->instrument))] = p->terminal.path();
    std::cout << ready.dump() << std::endl;  // flushed: a client waits for this line

    std::vector<pollfd> fds;
    std::vector<Target> targets;
    std::array<char, kReadChunkBytes> buffer;
    GuardPhase("its polls");
    while (!stopped()) {
      Turned();
      int64_t now_ns = MonotonicNs();
      fds.clear();
      targets.clear();
      const auto watch = [&](int fd, short events, Target target) {
        fds.push_back(pollfd{fd, events, 0});
        targets.push_back(target);
      };
      watch(wakeup_.fd(), POLLIN, Target{Target::Kind::kWakeup, 0});
      for (size_t i = 0; i < listeners_.size(); ++i) watch(listeners_[i].socket.get(), POLLIN, {Target::Kind::kListener, i});
      for (size_t i = 0; i < ptys_.size(); ++i) {
        const bool output = ptys_[i]->session && !core_.Output(*ptys_[i]->session, now_ns).empty();
        watch(ptys_[i]->terminal.master(), static_cast<short>(POLLIN | (output ? POLLOUT : 0)), {Target::Kind::kPty, i});
      }
      for (const auto& [id, connection] : connections_) {
        const bool output = !core_.Output(id, now_ns).empty();
        watch(connection.socket.get(), static_cast<short>(POLLIN | (output ? POLLOUT : 0)),
              {Target::Kind::kConnection, static_cast<size_t>(id)});
      }
      const int64_t wait_ns = std::clamp<int64_t>(core_.NextDueNs() - now_ns, 0, kMaxIdleNs);
      const timespec timeout{0, static_cast<long>(wait_ns)};
      if (::ppoll(fds.data(), fds.size(), &timeout, nullptr) < 0 && errno != EINTR) {
        throw std::runtime_error(fmt::format("ppoll: {}", std::strerror(errno)));
      }
      now_ns = MonotonicNs();
      core_.Advance(now_ns);
      for (size_t i = 0; i < fds.size(); ++i) {
        if (fds[i].revents == 0) continue;
        const Target& target = targets[i];
        switch (target.kind) {
          case Target::Kind::kWakeup: wakeup_.Drain(); break;
          case Target::Kind::kListener: Accept(listeners_[target.index], now_ns); break;
          case Target::Kind::kPty: ReadPty(*ptys_[target.index], buffer.data(), now_ns); break;
          case Target::Kind::kConnection:
            ReadConnection(static_cast<EmulatorCore::SessionId>(target.index), fds[i].revents, buffer.data(), now_ns);
            break;
        }
      }
      for (EmulatorCore::SessionId id : core_.TakeEnded()) Drop(id);
      for (auto& pty : ptys_) {
        // A pseudo-terminal has no connection to refuse: it answers again once the instrument
        // is reachable, as a real one after its cable is back.
        if (!pty->session && core_.Reachable(pty->instrument, now_ns)) pty->session = core_.Open(pty->instrument, now_ns);
      }
      WriteAll(now_ns);
    }
    return cli::ExitCode::kOk;
  }

 private:
  struct Listener {
    Instrument instrument;
    FileDescriptor socket;
    int port;
  };
  struct Connection {
    Instrument instrument;
    FileDescriptor socket;
  };
  struct PtyEndpoint {
    Instrument instrument;
    PseudoTerminal terminal;
    std::optional<EmulatorCore::SessionId> session;
  };
  /// What a pollfd stands for.
  struct Target {
    enum class Kind { kWakeup, kListener, kPty, kConnection } kind;
    size_t index;  ///< listener, pty, or the connection's session id
  };

  void OnStop() override { wakeup_.Signal(); }

  void Log(const std::string& kind, const std::string& text) {
    // Keyed by the kind and the first word (the control command, the instrument), so that one
    // client in a loop cannot flood the log and the rest still shows.
    log_.Log(spdlog::level::info, kind + " " + text.substr(0, text.find(' ')), text);
  }

  void Accept(Listener& listener, int64_t now_ns) {
    for (int i = 0; i < kAcceptsPerWakeup; ++i) {
      int error = 0;
      FileDescriptor socket = AcceptConnection(listener.socket.get(), &error);
      if (!socket.valid()) {
        if (error != 0) {
          log_.Log(spdlog::level::warn, "accept", fmt::format("accept on port {}: {}", listener.port, std::strerror(error)));
        }
        return;
      }
      const std::optional<EmulatorCore::SessionId> id = core_.Open(listener.instrument, now_ns);
      if (!id) {
        Log("refused", fmt::format("{}: a connection refused (unreachable, or {} connections open)",
                                   InstrumentName(listener.instrument), EmulatorCore::kMaxSessionsPerInstrument));
        continue;  // closed as it goes out of scope
      }
      Log("connected", fmt::format("{}: a client connected", InstrumentName(listener.instrument)));
      connections_.emplace(*id, Connection{listener.instrument, std::move(socket)});
    }
  }

  void ReadConnection(EmulatorCore::SessionId id, short revents, char* buffer, int64_t now_ns) {
    const auto it = connections_.find(id);
    if (it == connections_.end()) return;
    if ((revents & (POLLIN | POLLHUP | POLLERR)) == 0) return;  // writable only: WriteAll
    const IoResult read = ReadSome(it->second.socket.get(), buffer, kReadChunkBytes);
    if (read.kind == IoResult::Kind::kClosed) {
      Log("disconnected", fmt::format("{}: a client disconnected", InstrumentName(it->second.instrument)));
      core_.Close(id);
      connections_.erase(it);
      return;
    }
    if (read.bytes > 0) core_.Receive(id, std::string_view(buffer, read.bytes), now_ns);
  }

  void ReadPty(PtyEndpoint& pty, char* buffer, int64_t now_ns) {
    const IoResult read = ReadSome(pty.terminal.master(), buffer, kReadChunkBytes);
    if (read.kind == IoResult::Kind::kClosed) {
      // Not a client leaving (the emulator holds the slave open itself): the terminal broke, and
      // polling it again would only spin.
      throw std::runtime_error(fmt::format("{}: the pseudo-terminal {} failed: {}", InstrumentName(pty.instrument),
                                           pty.terminal.path(), std::strerror(errno)));
    }
    // While the instrument is unreachable the bytes are read and dropped: nobody listens.
    if (read.bytes > 0 && pty.session) core_.Receive(*pty.session, std::string_view(buffer, read.bytes), now_ns);
  }

  /// A session the core ended: close its connection, or make its pseudo-terminal forget.
  void Drop(EmulatorCore::SessionId id) {
    connections_.erase(id);
    for (auto& pty : ptys_) {
      if (pty->session == id) {
        pty->terminal.Flush();
        pty->session.reset();
      }
    }
  }

  void WriteAll(int64_t now_ns) {
    for (auto it = connections_.begin(); it != connections_.end();) {
      const std::string_view out = core_.Output(it->first, now_ns);
      const IoResult wrote = out.empty() ? IoResult{} : WriteSome(it->second.socket.get(), out, true);
      if (wrote.kind == IoResult::Kind::kClosed) {
        core_.Close(it->first);
        it = connections_.erase(it);
        continue;
      }
      if (wrote.bytes > 0) core_.Written(it->first, wrote.bytes);
      ++it;
    }
    for (auto& pty : ptys_) {
      if (!pty->session) continue;
      const std::string_view out = core_.Output(*pty->session, now_ns);
      if (out.empty()) continue;
      const IoResult wrote = WriteSome(pty->terminal.master(), out, false);
      if (wrote.bytes > 0) core_.Written(*pty->session, wrote.bytes);
    }
  }

  EmulatorCore core_;
  LogLimiter log_;
  Wakeup wakeup_;
  std::vector<Listener> listeners_;
  std::vector<std::unique_ptr<PtyEndpoint>> ptys_;
  std::map<EmulatorCore::SessionId, Connection> connections_;
};

}  // namespace
}  // namespace dpc::services

int main(int argc, char** argv) {
  return dpc::services::ServiceMain<dpc::services::EmulatorService>(
      argc, argv, "dpc-emulator: an EPC and a polarimeter emulated on a scenario's true device, over TCP and ptys");
}
