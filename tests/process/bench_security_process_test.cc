// The secure bench as real processes: the three services with DDS Security (a bench PKI made
// by deploy/security/make-bench-pki.sh), watched by the observer identity, attacked by
// participants without credentials, with a certificate of another CA, an expired certificate,
// tampered governance or permissions, and by legitimate identities doing what their
// permissions do not grant. Each attack gets 0 matched readers and 0 applied data, while the
// bench keeps locking. Domain 48; loopback only.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "support/bench_fixture.h"

namespace dpc {
namespace {

using dpc::testing::Eventually;
using dpc::testing::Process;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

std::string g_pki;            ///< the bench's credentials
std::string g_other_ca;       ///< another CA's bench
std::string g_tampered_governance;
std::string g_tampered_permissions;
std::string g_setup_error;

bool Shell(const std::string& command) { return std::system((command + " >>" + g_pki + ".log 2>&1").c_str()) == 0; }

/// Copies `dir` to `copy` and replaces the first `from` in `file` (inside it) by `to`.
bool TamperedCopy(const std::string& dir, const std::string& copy, const std::string& file, const std::string& from,
                  const std::string& to) {
  fs::remove_all(copy);
  fs::copy(dir, copy, fs::copy_options::recursive);
  const fs::path path = fs::path(copy) / file;
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::string content = text.str();
  const size_t at = content.find(from);
  if (at == std::string::npos) return false;
  content.replace(at, from.size(), to);
  std::ofstream(path, std::ios::trunc) << content;
  return true;
}

class BenchSecurityTest : public dpc::testing::BenchFixture {
 protected:
  static void SetUpTestSuite() {
    const std::string base = ::testing::TempDir() + "dpc_security_" + std::to_string(getpid());
    fs::remove_all(base);
    fs::create_directories(base);
    g_pki = base + "/bench";
    g_other_ca = base + "/other";
    g_tampered_governance = base + "/tampered_governance";
    g_tampered_permissions = base + "/tampered_permissions";
    const std::string script = std::string(DPC_SOURCE_DIR) + "/deploy/security/make-bench-pki.sh";
    if (!Shell(script + " --out " + g_pki + " --controllers main,standby,late --expired controller-late") ||
        !Shell(script + " --out " + g_other_ca + " --controllers main")) {
      g_setup_error = "make-bench-pki.sh failed: " + g_pki + ".log";
      return;
    }
    // Governance: the topic rule's expression (signed text) changed; permissions: main's grant
    // widened to every controller's partition.
    if (!TamperedCopy(g_pki, g_tampered_governance, "governance.p7s", "<topic_expression>dpc_*",
                      "<topic_expression>dpc_x") ||
        !TamperedCopy(g_pki, g_tampered_permissions, "controller-main/permissions.p7s", "dpc.bench1.controller.main",
                      "dpc.bench1.controller.*")) {
      g_setup_error = "could not tamper with the copies (layout of make-bench-pki.sh changed?)";
    }
  }

  void SetUp() override {
    ASSERT_TRUE(g_setup_error.empty()) << g_setup_error;
    common_args_ = {"--security-dir", g_pki};
    StartObserver(48, {g_pki, "observer"});
    Process& driver = StartDriver();
    Process* controller = &StartController("main", 10);
    Process* polarimeter = &StartPolarimeter({"--rate-hz", "1000"});
    if (!Eventually([&] { return AppliedBy("main") > 200; }, 15s)) {
      // Fast DDS 2.9: the security handshake of two participants that start at the same instant
      // can stall for good — both discovered each other, neither ever reports the other
      // authenticated (seen about once in twenty starts of this fixture). An operator's remedy
      // is a restart of one of them; the fixture does that once for the service whose
      // handshake with the driver (or the polarimeter's with the controller) did not finish, and
      // says so. A second stall fails the test.
      const auto authenticated_by = [&](const Process& by, const std::string& name) {
        const std::string log = by.Log();
        for (size_t at = log.find("participant authenticated:"); at != std::string::npos;
             at = log.find("participant authenticated:", at + 1)) {
          if (log.substr(at, log.find('\n', at) - at).find("(" + name + ")") != std::string::npos) return true;
        }
        return false;
      };
      for (auto [process, name, restart] :
           {std::tuple<Process**, std::string, std::function<Process&()>>{
                &polarimeter, "dpc-polarimeter/bench1",
                [&]() -> Process& { return StartPolarimeter({"--rate-hz", "1000"}, "polarimeter_restarted"); }},
            {&controller, "dpc-controller/main", [&]() -> Process& {
               return Start(DPC_CONTROLLER_BINARY, {"--id", "main", "--priority", "10"}, "controller_main_restarted");
             }}}) {
        const bool with_driver = authenticated_by(driver, name);
        if (with_driver && (process != &polarimeter || authenticated_by(*controller, name))) continue;
        std::fprintf(stderr, "note: the %s's security handshake with %s did not finish in 15 s (a Fast DDS 2.9 "
                             "stall); restarting it once\n", with_driver ? "controller" : "driver", name.c_str());
        (*process)->Signal(SIGTERM);
        (*process)->Wait(10s);
        *process = &restart();
      }
    }
    ASSERT_TRUE(Eventually([&] { return AppliedBy("main") > 200; }, 30s)) << Logs();
  }

  /// An attacker: a participant with `security`, writing `Message` (bench1, `controller_id`'s
  /// partition for commands) with `fill`ed data for 1.5 s. Returns how many readers its writer
  /// ever matched (0 if Fast DDS refused the participant or the writer: both are refusals).
  /// `until_matched`: for a legitimate participant (a control), up to 6 s, ending once matched:
  /// a new secure participant's handshakes take about 1 s on loopback, longer under load.
  template <typename Message>
  int Attack(const bus::SecurityOptions& security, const std::string& controller_id,
             const std::function<void(Message*)>& fill, std::string* how, bool until_matched = false) {
    std::unique_ptr<bus::BusParticipant> participant;
    std::unique_ptr<bus::Writer<Message>> writer;
    try {
      participant = std::make_unique<bus::BusParticipant>(bus::BusOptions{48, "dpc-test-attacker", security});
      writer = participant->MakeWriter<Message>("bench1", controller_id);
    } catch (const bus::BusError& e) {
      *how = std::string("refused at creation: ") + e.what();
      return 0;
    }
    int matched = 0;
    const auto end = std::chrono::steady_clock::now() + (until_matched ? 6000ms : 1500ms);
    while (std::chrono::steady_clock::now() < end && !(until_matched && matched > 0)) {
      Message message;
      fill(&message);
      writer->Write(message);
      matched = std::max(matched, writer->matched_readers());
      std::this_thread::sleep_for(2ms);
    }
    *how = "created; matched " + std::to_string(matched) + " readers";
    writer.reset();
    participant.reset();
    return matched;
  }

  /// A command of `id` with a priority that would win and φ no controller commands.
  std::function<void(msg::WaveplateCommand*)> Spoof(const std::string& id, int priority = 1000) {
    return [this, id, priority](msg::WaveplateCommand* c) {
      c->bench_id("bench1");
      c->controller_id(id);
      c->priority(priority);
      auto state = LatestState();
      c->answers_sample(state ? state->answers_sample() + 1 : 1);
      c->phi({0.9, 0.9, 0.9});
    };
  }

  /// The control of an attack: the standby identity of `pki`, commanding in its own partition
  /// with a low priority (main stays obeyed), is matched by the driver; how many readers. A new
  /// participant's handshake with the driver can stall for good (Fast DDS 2.9, see SetUp; seen
  /// once in CI: 0 readers in 6 s): the remedy, a new participant, is tried at most twice more,
  /// and said.
  int StandbyMatched(const std::string& pki, std::string* how) {
    int matched = 0;
    for (int attempt = 0; attempt < 3 && matched == 0; ++attempt) {
      if (attempt > 0) {
        std::fprintf(stderr, "note: the standby matched no reader in 6 s (%s; a Fast DDS 2.9 handshake stall?); "
                             "a new participant\n", how->c_str());
      }
      matched = Attack<msg::WaveplateCommand>({pki, "controller-standby"}, "standby", Spoof("standby", -5), how,
                                              /*until_matched=*/true);
    }
    return matched;
  }

  /// No state ever applied the attackers' φ, and the bench still follows main.
  void ExpectUntouched(size_t applied_before) {
    for (const auto& s : States()) {
      for (double v : s.state.phi_applied()) ASSERT_NE(v, 0.9) << "an attacker's command was applied";
    }
    EXPECT_TRUE(SoonObeys("main")) << LatestState()->reason().to_string();
    EXPECT_GT(AppliedBy("main"), applied_before + 500) << "the bench kept locking throughout";
  }
};

TEST_F(BenchSecurityTest, NoOneWithoutTheBenchsCredentialsOrTheRightPermissionIsMatched) {
  const size_t applied_before = AppliedBy("main");
  struct Case {
    const char* name;
    bus::SecurityOptions security;
    std::string id;
  };
  const std::vector<Case> command_attacks = {
      {"no credentials", {}, "main"},
      {"a certificate of another CA", {g_other_ca, "controller-main"}, "main"},
      {"an expired certificate", {g_pki, "controller-late"}, "late"},
      {"tampered governance", {g_tampered_governance, "controller-main"}, "main"},
      {"tampered permissions", {g_tampered_permissions, "controller-main"}, "main"},
      {"an observer publishing commands", {g_pki, "observer"}, "observer"},
      {"a controller commanding in another controller's partition", {g_pki, "controller-standby"}, "main"},
  };
  for (const Case& attack : command_attacks) {
    std::string how;
    EXPECT_EQ(Attack<msg::WaveplateCommand>(attack.security, attack.id, Spoof(attack.id), &how), 0)
        << attack.name << ": " << how;
    std::printf("%-60s %s\n", attack.name, how.c_str());
  }
  // Forged authority: a target and a device description from anyone but the driver.
  std::string how;
  auto forged_target = [](msg::Target* t) {
    t->bench_id("bench1");
    t->revision(~0ULL);
  };
  EXPECT_EQ(Attack<msg::Target>({g_pki, "controller-standby"}, "", forged_target, &how), 0)
      << "a controller publishing a target: " << how;
  std::printf("%-60s %s\n", "a controller publishing a target", how.c_str());
  EXPECT_EQ(Attack<msg::Target>({}, "", forged_target, &how), 0) << "no credentials, a target: " << how;
  EXPECT_EQ(Attack<msg::DeviceDescription>({g_pki, "operator"}, "",
                                           [](msg::DeviceDescription* d) { d->bench_id("bench1"); }, &how),
            0)
      << "an operator publishing a device description: " << how;
  EXPECT_EQ(Attack<msg::StokesSample>({g_pki, "controller-standby"}, "",
                                      [](msg::StokesSample* s) {
                                        s->bench_id("bench1");
                                        s->sequence_number(~0ULL - 1);
                                        s->s_in({1.0, 0.0, 0.0});
                                        s->s_out({1.0, 0.0, 0.0});
                                      },
                                      &how),
            0)
      << "a controller publishing samples: " << how;
  EXPECT_EQ(Attack<msg::WaveplateState>({}, "", [](msg::WaveplateState* s) { s->bench_id("bench1"); }, &how), 0)
      << "no credentials, a state: " << how;
  ExpectUntouched(applied_before);
  // The control: the standby's own identity, in its own partition, is matched (a low priority,
  // so that main stays obeyed).
  EXPECT_GT(StandbyMatched(g_pki, &how), 0) << "the legitimate standby: " << how;
}

/// The running service whose log is `name`.log (the fixture's restart after a handshake stall
/// is `name`_restarted).
Process& Service(std::vector<std::unique_ptr<Process>>& processes, const std::string& name) {
  Process* found = nullptr;
  for (auto& p : processes) {
    const std::string stem = p->out_path().stem().string();
    if (stem == name || stem == name + "_restarted") found = p.get();
  }
  if (found == nullptr) throw std::runtime_error("no process " + name);
  return *found;
}

/// How many samples the observer saw answered by states applying a command of `id` (a holding
/// driver's heartbeats repeat the last one: not counted again).
size_t SamplesAnsweredBy(const std::vector<dpc::testing::SeenState>& states, const std::string& id) {
  std::set<uint64_t> samples;
  for (const auto& s : states) {
    if (s.state.answers_sample() > 0 && s.state.applied_controller_id().to_string() == id) {
      samples.insert(s.state.answers_sample());
    }
  }
  return samples.size();
}

/// How many times `text` is in `log`.
size_t Count(const std::string& log, const std::string& text) {
  size_t n = 0;
  for (size_t at = log.find(text); at != std::string::npos; at = log.find(text, at + 1)) ++n;
  return n;
}

// Credentials rotated while the bench runs: with --keep-replaced the old certificates stay valid
// while each service, on SIGHUP, makes its participant again with its new identity; then
// --revoke-replaced and a second SIGHUP each load the revocation list. No service restarts, the
// bench keeps locking after each reload, and a participant holding a replaced certificate is
// refused by every service (before reloads, a driver that started before a rotation obeyed it).
// Credentials that do not give a participant (a tampered grant) are refused by the reload and
// the running participant is kept.
TEST_F(BenchSecurityTest, RotatedCredentialsTakeEffectOnSighupWithoutARestart) {
  const std::string script = std::string(DPC_SOURCE_DIR) + "/deploy/security/make-bench-pki.sh";
  Process& driver = Service(processes_, "driver");
  Process& controller = Service(processes_, "controller_main");
  Process& polarimeter = Service(processes_, "polarimeter");
  const std::string reloaded = "endpoints are on the new participant";
  // Each reload: the service says it moved, and the bench locks again under main. A reloaded
  // participant's handshake with a peer can stall for good, as a starting one's can (Fast DDS
  // 2.9, see SetUp; seen once in about ten runs: the new controller never authenticated by the
  // polarimeter): the remedy, another SIGHUP, is sent once, and said.
  std::map<const Process*, size_t> reloads;
  const auto reload = [&](Process& service, const char* what) {
    const size_t answered = SamplesAnsweredBy(States(), "main");
    const int64_t sent_ns = MonotonicNs();
    const auto signal = [&] {
      const size_t before = Count(service.Log(), reloaded);
      service.Signal(SIGHUP);
      ++reloads[&service];
      return Eventually([&] { return Count(service.Log(), reloaded) > before; }, 20s);
    };
    ASSERT_TRUE(signal()) << what << " did not reload\n" << Logs();
    if (!Eventually([&] { return SamplesAnsweredBy(States(), "main") > answered + 200; }, 15s)) {
      std::fprintf(stderr, "note: the bench did not lock again within 15 s of the %s's reload (a Fast DDS 2.9 "
                           "handshake stall?); SIGHUP once more\n", what);
      ASSERT_TRUE(signal()) << what << " did not reload\n" << Logs();
    }
    ASSERT_TRUE(Eventually([&] { return SamplesAnsweredBy(States(), "main") > answered + 200; }, 30s))
        << "the bench did not lock again after the " << what << "'s reload\n" << Logs();
    // The longest pause, from the signal on, between main's commands applied to new samples
    // (states answering a later sample than any before; as the observer received them).
    int64_t longest_ns = 0, last_ns = sent_ns;
    uint64_t newest_sample = 0;
    for (const auto& s : States()) {
      if (s.state.answers_sample() <= newest_sample || s.state.applied_controller_id().to_string() != "main") {
        continue;
      }
      newest_sample = s.state.answers_sample();
      if (s.seen_ns < sent_ns) continue;
      longest_ns = std::max(longest_ns, s.seen_ns - last_ns);
      last_ns = s.seen_ns;
    }
    std::printf("reload of the %-12s longest pause between main's commands applied: %.0f ms\n", what,
                longest_ns * 1e-6);
    EXPECT_TRUE(service.running()) << what << " exited";
  };

  // A reload that cannot make a participant (the driver's grant no longer matches its
  // signature) is refused; the bench goes on as it was.
  const fs::path grant = fs::path(g_pki) / "driver" / "permissions.p7s";
  const fs::path saved = fs::path(g_pki) / "driver" / "permissions.p7s.saved";
  fs::copy_file(grant, saved, fs::copy_options::overwrite_existing);
  ASSERT_TRUE(TamperedCopy(g_pki, g_pki + ".tampered", "driver/permissions.p7s", "dpc.bench1", "dpc.benchX"));
  fs::copy_file(fs::path(g_pki + ".tampered") / "driver" / "permissions.p7s", grant,
                fs::copy_options::overwrite_existing);
  {
    const size_t answered = SamplesAnsweredBy(States(), "main");
    driver.Signal(SIGHUP);
    EXPECT_TRUE(Eventually([&] { return driver.Log().find("reload (SIGHUP) refused") != std::string::npos; }, 20s))
        << driver.Log();
    EXPECT_TRUE(Eventually([&] { return SamplesAnsweredBy(States(), "main") > answered + 500; }, 20s)) << Logs();
    EXPECT_EQ(Count(driver.Log(), reloaded), 0u);
  }
  fs::copy_file(saved, grant, fs::copy_options::overwrite_existing);

  // Phase 1: new identities, the old ones still valid; every service moves to its new one.
  const std::string before_rotation = g_pki + ".before_rotation";
  fs::remove_all(before_rotation);
  fs::copy(g_pki, before_rotation, fs::copy_options::recursive);
  ASSERT_TRUE(Shell(script + " --out " + g_pki + " --rotate --keep-replaced"));
  reload(polarimeter, "polarimeter");
  reload(controller, "controller");
  reload(driver, "driver");
  RestartObserver({g_pki, "observer"});
  // Phase 2: the replaced certificates revoked; every service loads the list.
  ASSERT_TRUE(Shell(script + " --out " + g_pki + " --revoke-replaced"));
  reload(polarimeter, "polarimeter");
  reload(controller, "controller");
  reload(driver, "driver");

  // A copy of a replaced key is useless now: the old standby identity, commanding with a
  // priority that would win, is matched by no service. The new one is (a low priority).
  std::string how;
  EXPECT_EQ(Attack<msg::WaveplateCommand>({before_rotation, "controller-standby"}, "standby", Spoof("standby"), &how),
            0)
      << "a replaced certificate: " << how;
  std::printf("%-60s %s\n", "a replaced (revoked) certificate commanding", how.c_str());
  for (const auto& s : States()) {
    for (double v : s.state.phi_applied()) ASSERT_NE(v, 0.9) << "the replaced certificate's command was applied";
  }
  EXPECT_TRUE(SoonObeys("main")) << LatestState()->reason().to_string();
  EXPECT_GT(StandbyMatched(g_pki, &how), 0) << "the rotated standby: " << how;
  for (Process* p : {&driver, &controller, &polarimeter}) {
    EXPECT_EQ(Count(p->Log(), reloaded), reloads[p]) << p->out_path();
  }
}

TEST_F(BenchSecurityTest, AParticipantWithoutCredentialsSeesNothing) {
  bus::BusParticipant eavesdropper(bus::BusOptions{48, "dpc-test-eavesdropper", {}});
  auto states = eavesdropper.MakeReader<msg::WaveplateState>("bench1", [](const auto&, const auto&) {});
  auto samples = eavesdropper.MakeReader<msg::StokesSample>("bench1", [](const auto&, const auto&) {});
  std::this_thread::sleep_for(2s);
  EXPECT_EQ(states->counters().matched_writers.load(), 0);
  EXPECT_EQ(states->counters().samples.load(), 0u);
  EXPECT_EQ(samples->counters().matched_writers.load(), 0);
  EXPECT_EQ(samples->counters().samples.load(), 0u);
  EXPECT_TRUE(SoonObeys("main"));
  // The operator sees the refusal in the services' logs, naming the intruder.
  EXPECT_TRUE(Eventually(
      [&] {
        const std::string driver_log = processes_.front()->Log();
        return driver_log.find("participant refused by DDS Security") != std::string::npos &&
               driver_log.find("(dpc-test-eavesdropper)") != std::string::npos;
      },
      5s))
      << Logs();
  // Refused again at each of its announcements (every second), it is named once.
  const std::string driver_log = processes_.front()->Log();
  std::istringstream lines(driver_log);
  size_t refusals = 0;
  for (std::string line; std::getline(lines, line);) {
    refusals += line.find("refused by DDS Security") != std::string::npos &&
                line.find("(dpc-test-eavesdropper)") != std::string::npos;
  }
  EXPECT_EQ(refusals, 1u) << driver_log;
}

}  // namespace
}  // namespace dpc
