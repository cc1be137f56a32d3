// The secure bench as real processes: the three services with DDS Security (a bench PKI made
// by deploy/security/make-bench-pki.sh), watched by the observer identity, attacked by
// participants without credentials, with a certificate of another CA, an expired certificate,
// tampered governance or permissions, and by legitimate identities doing what their
// permissions do not grant. Each attack gets 0 matched readers and 0 applied data, while the
// bench keeps locking. Domain 48; loopback only.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
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
#include <vector>

#include "dpc/bus/handshake_watchdog.h"
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
    StartDriver();
    StartController("main", 10);
    StartPolarimeter({"--rate-hz", "1000"});
    // Fast DDS 2.9: the security handshake of two participants that start at the same instant
    // can stall for good (both discovered each other, neither ever reports the other
    // authenticated; seen about once in twenty starts of this fixture). The starved service
    // then makes its participant again by itself after about 4 s (bus::HandshakeWatchdog):
    // the bench locks within 40 s, and the test says when that happened. A stall between a
    // working service and the test's observer, which the service does not heal, the observer
    // heals (seen once in 17 starts: the driver obeyed main, the observer saw no state in 40 s).
    ASSERT_TRUE(Eventually(
        [&] {
          HealObserverStall();
          return AppliedBy("main") > 200;
        },
        40s))
        << Logs();
    NoteHandshakeStallReloads();
  }

  /// Says on stderr, once each, the lines where a service healed a handshake stall by itself.
  void NoteHandshakeStallReloads() {
    for (const auto& p : processes_) {
      const std::string log = p->Log();
      for (size_t at = log.find(kStallWarning); at != std::string::npos; at = log.find(kStallWarning, at + 1)) {
        const size_t begin = log.rfind('\n', at) + 1;  // npos + 1 = 0
        if (!noted_.insert({p->out_path().string(), begin}).second) continue;
        std::fprintf(stderr, "note: %s healed a handshake stall: %s\n", p->out_path().stem().c_str(),
                     log.substr(begin, log.find('\n', at) - begin).c_str());
      }
    }
  }
  static constexpr const char* kStallWarning = "(a Fast DDS 2.9 handshake stall, or a peer that never answers)";
  std::set<std::pair<std::string, size_t>> noted_;

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

/// The running service whose log is `name`.log.
Process& Service(std::vector<std::unique_ptr<Process>>& processes, const std::string& name) {
  Process* found = nullptr;
  for (auto& p : processes) {
    const std::string stem = p->out_path().stem().string();
    if (stem == name) found = p.get();
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
  const std::string reloaded = "reload (SIGHUP): the endpoints are on the new participant";
  // Each reload: the service says it moved, and the bench locks again under main. A reloaded
  // participant's handshake with a peer can stall for good, as a starting one's can (Fast DDS
  // 2.9, see SetUp; seen once in about thirty reloads: the new controller never authenticated
  // by the polarimeter); the starved service heals it (NoteHandshakeStallReloads says so).
  std::map<const Process*, size_t> reloads;
  const auto reload = [&](Process& service, const char* what) {
    const size_t answered = SamplesAnsweredBy(States(), "main");
    const int64_t sent_ns = MonotonicNs();
    const size_t before = Count(service.Log(), reloaded);
    const auto refusals = [&] {
      size_t n = 0;
      for (const auto& p : processes_) n += Count(p->Log(), "refused: the bench's");
      return n;
    };
    const size_t refusals_before = refusals();
    service.Signal(SIGHUP);
    ++reloads[&service];
    ASSERT_TRUE(Eventually([&] { return Count(service.Log(), reloaded) > before; }, 20s))
        << what << " did not reload\n" << Logs();
    // A stalled handshake with the reloaded participant heals by itself (the starved service
    // makes its participant again after about 4 s): said, and its pause printed with the rest.
    ASSERT_TRUE(Eventually([&] { return SamplesAnsweredBy(States(), "main") > answered + 200; }, 40s))
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
    // Its peers take the new participant's data once the old one has left (SourceBinding): a
    // refusal is logged only for data that arrived before the old one's goodbye.
    std::printf("reload of the %-12s longest pause between main's commands applied: %.0f ms; %zu refusal lines\n",
                what, longest_ns * 1e-6, refusals() - refusals_before);
    NoteHandshakeStallReloads();
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

// A reload whose new participant does not authenticate every peer of the old one in
// kMaxPrepareNs (its handshakes stalled, or the peer stopped answering) tries another new
// participant, while the old one serves on: here the controller is stopped (SIGSTOP) as the
// driver reloads, so no new participant of the driver can authenticate it until the old one's
// lease on it (5 s in the loopback profile) expires; the driver then moves to its second new
// participant, and obeys the controller again once it runs again (a peer that had let the
// controller's lease expire too makes its participant again if it must: see the end).
TEST_F(BenchSecurityTest, AReloadTriesAnotherNewParticipantWhenTheFirstMissesAPeer) {
  Process& driver = Service(processes_, "driver");
  Process& controller = Service(processes_, "controller_main");
  const std::string another = "reload (SIGHUP): the new participant did not authenticate the old one's peers in 3 s";
  const std::string moved = "reload (SIGHUP): the endpoints are on the new participant";
  controller.Signal(SIGSTOP);
  struct Continue {
    Process& p;
    ~Continue() { p.Signal(SIGCONT); }
  } resume{controller};
  driver.Signal(SIGHUP);
  ASSERT_TRUE(Eventually([&] { return Count(driver.Log(), moved) > 0; }, 15s)) << driver.Log();
  const std::string log = driver.Log();
  const size_t first = log.find(another);
  ASSERT_NE(first, std::string::npos) << log;
  // It names the peer it missed (the controller), and the reload goes on with a second one.
  const std::string line = log.substr(first, log.find('\n', first) - first);
  EXPECT_NE(line.find("; not yet "), std::string::npos) << line;
  EXPECT_NE(line.find("another new participant (2 of at most 3)"), std::string::npos) << line;
  const size_t move = log.find(moved);
  EXPECT_GT(move, first) << log;
  std::printf("%s\n", log.substr(move, log.find('\n', move) - move).c_str());
  EXPECT_NE(log.find(" new participants: it authenticated ", move), std::string::npos) << log;
  // Back, the controller is a peer whose lease the others let expire: one that still holds its
  // side of the old handshake (the polarimeter's, say) makes its participant again to be
  // handshaken afresh (HandshakeWatchdog::JudgeReturning), and the bench locks again.
  // The controller resumes with every peer's lease expired and the driver's old participant's
  // dispose waiting in its socket: both at once can deadlock its participant (Fast DDS 2.9, see
  // bus/event_thread_canary.h; seen once in many runs). Its loop guard then ends it, naming the
  // event thread, for a supervisor to restart it (compose's restart policy): the test does what
  // the supervisor would, once, and says so. Any other end of a service fails the test.
  controller.Signal(SIGCONT);
  const int64_t resumed_ns = MonotonicNs();
  const std::string stuck = "stuck: the event thread of its DDS participant";
  std::string unexpected_end;
  bool restarted = false;
  EXPECT_TRUE(Eventually(
      [&] {
        for (const auto& p : processes_) {
          if (!unexpected_end.empty() || (restarted && p.get() == &controller) || p->running()) continue;
          if (restarted || p.get() != &controller || controller.Log().find(stuck) == std::string::npos) {
            unexpected_end = p->out_path().string();
            continue;
          }
          restarted = true;
          std::printf("the controller ended itself %.1f s after it resumed (its event thread stuck); restarted\n",
                      (MonotonicNs() - resumed_ns) * 1e-9);
          Start(DPC_CONTROLLER_BINARY, {"--id", "main", "--priority", "10"}, "controller_main_restarted");
          break;  // processes_ grew
        }
        return !unexpected_end.empty() || SoonObeys("main", 100ms);
      },
      30s))
      << Logs();
  EXPECT_EQ(unexpected_end, "") << "a service ended: " << Logs();
  std::printf("main obeyed again %.1f s after it resumed\n", (MonotonicNs() - resumed_ns) * 1e-9);
  for (const auto& p : processes_) {
    if (p->Log().find("back after its lease had expired") != std::string::npos) {
      std::printf("%s made its participant again for the returning controller\n", p->out_path().c_str());
    }
  }
  EXPECT_EQ(Count(driver.Log(), moved), 1u) << driver.Log();
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

/// A peer whose handshake never ends (as a stalled one, or one that stalls on purpose): the SPDP
/// announcement of a secure participant of this bench that is gone, sent again every 200 ms to
/// the domain's discovery group from a plain socket. The services discover it, start a
/// handshake, and never get an answer (nothing listens at its locators any more); its
/// announcements keep it alive.
class Ghost {
 public:
  explicit Ghost(int domain) : port_(static_cast<uint16_t>(7400 + 250 * domain)) {
    const int listener = socket(AF_INET, SOCK_DGRAM, 0);
    const int yes = 1;
    setsockopt(listener, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    setsockopt(listener, SOL_SOCKET, SO_REUSEPORT, &yes, sizeof yes);
    sockaddr_in any{};
    any.sin_family = AF_INET;
    any.sin_port = htons(port_);
    any.sin_addr.s_addr = htonl(INADDR_ANY);
    ip_mreq group{};
    group.imr_multiaddr.s_addr = inet_addr("239.255.0.1");
    group.imr_interface.s_addr = inet_addr("127.0.0.1");
    const timeval timeout{0, 200'000};
    if (bind(listener, reinterpret_cast<const sockaddr*>(&any), sizeof any) != 0 ||
        setsockopt(listener, IPPROTO_IP, IP_ADD_MEMBERSHIP, &group, sizeof group) != 0 ||
        setsockopt(listener, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout) != 0) {
      close(listener);
      throw std::runtime_error(std::string("ghost: cannot listen to the discovery group: ") + std::strerror(errno));
    }
    {
      bus::BusParticipant participant(bus::BusOptions{domain, "dpc-test-ghost", {g_pki, "observer"}});
      const auto& prefix = participant.raw()->guid().guidPrefix;
      guid_ = SourceName(bus::SourceOf(prefix));
      std::vector<uint8_t> datagram(65536);
      for (const auto end = std::chrono::steady_clock::now() + 5s;
           announcement_.empty() && std::chrono::steady_clock::now() < end;) {
        const ssize_t n = recv(listener, datagram.data(), datagram.size(), 0);
        // RTPS header: "RTPS", version, vendor, then the sender's GUID prefix (12 bytes).
        if (n >= 20 && std::memcmp(datagram.data(), "RTPS", 4) == 0 &&
            std::memcmp(datagram.data() + 8, prefix.value, 12) == 0) {
          announcement_.assign(datagram.begin(), datagram.begin() + n);
        }
      }
    }  // the participant is deleted: its locators close
    close(listener);
    if (announcement_.empty()) throw std::runtime_error("ghost: no announcement of its participant in 5 s");
    // Its deletion is processed by every service before the first replay: a replay that arrives
    // first is taken for the live participant, whose removal then comes after it, and later
    // replays (the same sequence number) were not discovered again (seen once in ten runs).
    std::this_thread::sleep_for(500ms);
    sender_ = std::thread([this] { Announce(); });
  }
  ~Ghost() {
    stop_ = true;
    sender_.join();
  }
  /// Its GUID prefix, as the services' logs write it.
  const std::string& guid() const { return guid_; }

 private:
  void Announce() {
    const int fd = socket(AF_INET, SOCK_DGRAM, 0);
    in_addr loopback{};
    loopback.s_addr = inet_addr("127.0.0.1");
    setsockopt(fd, IPPROTO_IP, IP_MULTICAST_IF, &loopback, sizeof loopback);
    sockaddr_in group{};
    group.sin_family = AF_INET;
    group.sin_port = htons(port_);
    group.sin_addr.s_addr = inet_addr("239.255.0.1");
    while (!stop_) {
      sendto(fd, announcement_.data(), announcement_.size(), 0, reinterpret_cast<const sockaddr*>(&group),
             sizeof group);
      std::this_thread::sleep_for(200ms);
    }
    close(fd);
  }

  uint16_t port_;
  std::string guid_;
  std::vector<uint8_t> announcement_;
  std::atomic<bool> stop_{false};
  std::thread sender_;
};

// A handshake with no outcome heals a starved service by itself, and never costs a working one:
// with the ghost pending, the locking bench makes no new participant; once its only controller
// is gone, the driver (no command applied for 4 s, the ghost's handshake pending as long) makes
// its participant again once, naming the ghost; a controller started then is obeyed at once.
TEST_F(BenchSecurityTest, AHandshakeWithoutOutcomeHealsAStarvedServiceAndNeverReloadsAWorkingOne) {
  Process& driver = Service(processes_, "driver");
  Process& main = Service(processes_, "controller_main");
  const std::string stall_reload = "reload (handshake stall): the endpoints are on the new participant";
  Ghost ghost(48);
  // The stall warnings that name the ghost (a real stall at the fixture's start may have made a
  // service heal, naming its real peer: that one is legitimate, and not counted).
  const auto naming_ghost = [&](const Process& p) {
    std::istringstream lines(p.Log());
    size_t n = 0;
    for (std::string line; std::getline(lines, line);) {
      n += line.find(kStallWarning) != std::string::npos && line.find(ghost.guid()) != std::string::npos;
    }
    return n;
  };
  // Discovered again after it left (its deletion), by every service.
  const auto discovered_again = [&](Process& p) {
    const std::string log = p.Log();
    const size_t gone = log.find("participant gone: " + ghost.guid());
    return gone != std::string::npos && log.find("participant discovered: " + ghost.guid(), gone) != std::string::npos;
  };
  ASSERT_TRUE(Eventually([&] { return discovered_again(driver) && discovered_again(main); }, 10s)) << Logs();
  const size_t applied = AppliedBy("main");
  // The ghost's handshake pending for twice as long as a stall takes to be judged.
  std::this_thread::sleep_for(std::chrono::nanoseconds(2 * bus::HandshakeWatchdog::kStallNs));
  for (const auto& p : processes_) {
    EXPECT_EQ(naming_ghost(*p), 0u) << p->out_path() << " reloaded for the ghost while it worked\n" << p->Log();
  }
  EXPECT_GT(AppliedBy("main"), applied + 4000) << "the bench kept locking";
  EXPECT_TRUE(SoonObeys("main"));

  main.Signal(SIGTERM);
  ASSERT_EQ(main.Wait(10s), 0);
  const int64_t starved_ns = MonotonicNs();
  const size_t reloads_before = Count(driver.Log(), stall_reload);
  ASSERT_TRUE(Eventually([&] { return Count(driver.Log(), stall_reload) > reloads_before; }, 25s))
      << "the starved driver did not heal\n" << driver.Log();
  const double after_s = (MonotonicNs() - starved_ns) * 1e-9;
  std::printf("the driver made its participant again %.1f s after its controller left\n", after_s);
  EXPECT_GE(after_s, bus::HandshakeWatchdog::kStallNs * 1e-9 - 1) << "too early: it did not starve for kStallNs";
  EXPECT_EQ(naming_ghost(driver), 1u) << "the warning names the ghost (and its name)\n" << driver.Log();
  EXPECT_NE(driver.Log().find("(dpc-test-ghost) has had no outcome"), std::string::npos) << driver.Log();

  Start(DPC_CONTROLLER_BINARY, {"--id", "main", "--priority", "10"}, "controller_main_again");
  // The test's observer sees the bench through its own handshake with the driver's new
  // participant, which can stall as any can (Fast DDS 2.9; seen once in about twenty runs): it
  // then makes its participant again, as a `dpc` command would.
  const auto observer_stalled = [&] {
    for (const std::string& peer : participant_->PendingHandshakes(5'000'000'000)) {
      if (peer.find(ghost.guid()) == std::string::npos) return peer;
    }
    return std::string();
  };
  ASSERT_TRUE(Eventually(
      [&] {
        if (const std::string peer = observer_stalled(); !peer.empty()) {
          std::fprintf(stderr, "note: the test's observer had no outcome of its handshake with %s in 5 s: "
                               "a new participant\n", peer.c_str());
          RestartObserver({g_pki, "observer"});
        }
        return SoonObeys("main", 100ms);
      },
      30s))
      << Logs();
  std::this_thread::sleep_for(2s);
  EXPECT_EQ(Count(driver.Log(), stall_reload), reloads_before + 1) << "one reload, then progress";
  EXPECT_TRUE(driver.running());
}

// A `dpc` command heals a stalled handshake too, and keeps what it had: `dpc record` and `dpc
// monitor`, started beside the ghost, hear nothing from it; after 4 s each makes its participant
// again (naming the ghost), and the recording goes on with the bench's samples, in the same file,
// as the monitor's lines do.
TEST_F(BenchSecurityTest, ADpcCommandHealsAStalledHandshakeAndKeepsRecording) {
  Ghost ghost(48);
  const std::string reloaded = "dpc record: reload (handshake stall): the endpoints are on the new participant";
  const std::string stuck_in_reload = "(stuck in: a reload of its DDS participant)";
  std::string file;
  int64_t start_ns = 0;
  Process* started_record = nullptr;
  Process* started_monitor = nullptr;
  for (int attempt = 1;; ++attempt) {
    const std::string again = attempt == 1 ? "" : "_again";
    file = dir_ + "/healed" + again + ".mcap";
    start_ns = MonotonicNs();
    started_record = &Start(DPC_BINARY, {"record", "--output", file, "--duration-s", "16"}, "record" + again);
    started_monitor =
        &Start(DPC_BINARY, {"monitor", "--lines", "--rate-hz", "2", "--duration-s", "16"}, "monitor" + again);
    // The stall is judged after 4 s; the endpoints move once the new participant has
    // authenticated the bench (about 1 s), at most 3 s later.
    ASSERT_TRUE(Eventually(
        [&] {
          const std::string log = started_record->Log();
          return Count(log, reloaded) > 0 || log.find(stuck_in_reload) != std::string::npos;
        },
        20s))
        << "dpc record did not heal\n" << started_record->Log();
    if (Count(started_record->Log(), reloaded) > 0) break;
    // Fast DDS 2.9 deadlocked inside the new participant while the endpoints moved to it (gdb: a
    // receive thread removing a departed peer in SecurityManager::remove_participant holds the
    // security lock while it waits for the event thread, which waits for that lock to send an
    // acknack; the main thread waits for it in register_local_reader). It never returns: the loop
    // guard ended the recorder, exit 1. Seen in 2 of about 30 runs; the heal is judged on a
    // second recorder.
    ASSERT_EQ(attempt, 1) << "Fast DDS deadlocked dpc record's reload twice in a row\n" << started_record->Log();
    EXPECT_EQ(started_record->Wait(20s), std::optional<int>(1)) << started_record->Log();
    std::fprintf(stderr, "note: Fast DDS 2.9 deadlocked dpc record's reload (its loop guard ended it); once more\n");
  }
  Process& record = *started_record;
  Process& monitor = *started_monitor;
  const double after_s = (MonotonicNs() - start_ns) * 1e-9;
  std::printf("dpc record made its participant again %.1f s after it started\n", after_s);
  EXPECT_GE(after_s, bus::HandshakeWatchdog::kStallNs * 1e-9 - 1)
      << "too early: the ghost was not pending for kStallNs";
  ASSERT_EQ(record.Wait(20s), 0) << record.Log();
  const std::string log = record.Log();
  const size_t warning = log.find(kStallWarning);
  ASSERT_NE(warning, std::string::npos) << log;
  const size_t line = log.rfind('\n', warning) + 1;
  // It names the ghost (and any real peer whose handshake stalled too: seen once). A real stall
  // between the recorder and a peer that started with it (the monitor) can be judged first, at a
  // look when the ghost, discovered a little later, has not been pending for kStallNs yet (seen
  // once): that heal is said, and counts as the one.
  const std::string named = log.substr(line, warning - line);
  if (named.find(ghost.guid() + " (dpc-test-ghost)") == std::string::npos) {
    std::fprintf(stderr, "note: dpc record healed a real stall first: %s\n", named.c_str());
    EXPECT_NE(named.find("the security handshake with "), std::string::npos) << log;
  }
  EXPECT_NE(log.find("so nothing of theirs reaches this command"), std::string::npos) << log;
  EXPECT_EQ(Count(log, reloaded), 1u) << "the next one not before 30 s\n" << log;
  // The samples counted in the status lines: before the reload, and at the end (1 kHz bench).
  const auto samples_in = [](const std::string& status) {
    const size_t at = status.find(", samples ");
    return at == std::string::npos ? -1L : std::stol(status.substr(at + 10));
  };
  const size_t reload_at = log.find(reloaded);
  const size_t status_before = log.rfind("dpc record: ", log.rfind(" s, ", reload_at));
  const long before = samples_in(log.substr(status_before, log.find('\n', status_before) - status_before));
  const size_t summary = log.find("dpc record: samples ");
  ASSERT_NE(summary, std::string::npos) << log;
  const long total = std::stol(log.substr(summary + 20));
  EXPECT_GT(before, 1000) << "it recorded before the reload\n" << log;
  EXPECT_GT(total, before + 4000) << "it recorded after the reload\n" << log;
  std::printf("samples recorded: %ld before the reload, %ld in all\n", before, total);
  // The file says when, and how many: `dpc info` reads it as complete.
  std::string out;
  FILE* info = popen((std::string(DPC_BINARY) + " info --json " + file).c_str(), "r");
  ASSERT_NE(info, nullptr);
  for (char buffer[4096]; const size_t n = fread(buffer, 1, sizeof buffer, info);) out.append(buffer, n);
  ASSERT_EQ(pclose(info), 0) << out;
  const nlohmann::json j = nlohmann::json::parse(out);
  EXPECT_EQ(j["complete"], true) << out;
  EXPECT_EQ(j["metadata"]["participant_reload"]["cause"], "handshake stall") << out;
  EXPECT_EQ(j["metadata"]["recording"]["participant_reloads"], "1") << out;
  EXPECT_EQ(j["metadata"]["recording"]["samples"], std::to_string(total)) << out;

  // `dpc monitor` healed too, and went on showing the bench's samples (1 kHz).
  ASSERT_EQ(monitor.Wait(5s), 0) << monitor.Log();
  const std::string shown = monitor.Log();
  const size_t monitor_reload = shown.find("dpc monitor: reload (handshake stall): the endpoints are on the new participant");
  ASSERT_NE(monitor_reload, std::string::npos) << shown;
  double rate_after_hz = 0;
  for (size_t at = shown.find("| rate_hz ", monitor_reload); at != std::string::npos;
       at = shown.find("| rate_hz ", at + 1)) {
    rate_after_hz = std::max(rate_after_hz, std::stod(shown.substr(at + 10)));
  }
  EXPECT_GT(rate_after_hz, 500) << shown;
}

}  // namespace
}  // namespace dpc
