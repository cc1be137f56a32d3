#pragma once
// Processes for the tests (and the bus benchmark) that start the project's real programs: a
// child with its stdout and stderr in files, signalled and reaped by PID, and always ended
// (SIGINT, then SIGKILL) when the object goes, so a failing test leaves nothing behind; and
// Eventually, the one way to wait for a condition (never a fixed sleep).
//
// Every child gets the loopback-only Fast DDS profile (deploy/fastdds/loopback.xml) unless the
// caller's environment names another, default SIGINT/SIGTERM dispositions and no blocked
// signal (a shell starts background jobs with SIGINT ignored), and /dev/null as its stdin.

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace dpc::testing {

/// Polls `condition` every 2 ms until it holds (true) or `timeout` passes (false).
inline bool Eventually(const std::function<bool()>& condition, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

/// A file's whole text ("" if it cannot be read).
inline std::string Slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

class Process {
 public:
  /// Starts `argv` (argv[0] a path) with stdout in `out_path` and stderr in `err_path` (empty:
  /// the same file). Throws std::runtime_error if it cannot be started.
  Process(std::vector<std::string> argv, std::filesystem::path out_path, std::filesystem::path err_path = {})
      : argv_(std::move(argv)), out_path_(std::move(out_path)), err_path_(std::move(err_path)) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (err_path_.empty()) {
      posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    } else {
      posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                       0644);
    }
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    sigset_t defaults, none;
    sigemptyset(&defaults);
    sigaddset(&defaults, SIGINT);
    sigaddset(&defaults, SIGTERM);
    sigemptyset(&none);
    posix_spawnattr_setsigdefault(&attributes, &defaults);
    posix_spawnattr_setsigmask(&attributes, &none);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
    std::vector<char*> args;
    for (std::string& a : argv_) args.push_back(a.data());
    args.push_back(nullptr);
    std::vector<std::string> environment = Environment();
    std::vector<char*> env;
    for (std::string& e : environment) env.push_back(e.data());
    env.push_back(nullptr);
    const int error = posix_spawn(&pid_, args[0], &actions, &attributes, args.data(), env.data());
    posix_spawnattr_destroy(&attributes);
    posix_spawn_file_actions_destroy(&actions);
    if (error != 0) {
      pid_ = -1;
      throw std::runtime_error("posix_spawn " + argv_[0] + ": " + std::strerror(error));
    }
  }
  ~Process() { Stop(); }
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  pid_t pid() const { return pid_; }
  bool running() { return pid_ > 0 && !Reap(); }
  void Signal(int signal) {
    if (running()) kill(pid_, signal);
  }
  /// Waits up to `timeout` for the exit: its exit code (128 + the signal if one ended it), or
  /// nullopt if it is still running.
  std::optional<int> Wait(std::chrono::milliseconds timeout) {
    Eventually([this] { return Reap(); }, timeout);
    return code_;
  }
  /// SIGINT, up to `grace` to exit, then SIGKILL. The exit code (-1 if it never started).
  int Stop(std::chrono::milliseconds grace = std::chrono::seconds(5)) {
    if (pid_ <= 0) return -1;
    if (!Reap()) {
      kill(pid_, SIGINT);
      if (!Wait(grace)) {
        kill(pid_, SIGKILL);
        Wait(std::chrono::seconds(5));
      }
    }
    return code_.value_or(-1);
  }

  /// CPU time the process has used so far (user + system, /proc/<pid>/stat), 0 once reaped.
  double cpu_seconds() const {
    std::ifstream stat("/proc/" + std::to_string(pid_) + "/stat");
    std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
    const size_t after_name = text.rfind(')');
    if (after_name == std::string::npos) return 0.0;
    std::istringstream fields(text.substr(after_name + 2));
    std::string field;
    long ticks = 0;
    for (int i = 3; i <= 15 && fields >> field; ++i) {
      if (i >= 14) ticks += std::stol(field);  // utime, stime
    }
    return static_cast<double>(ticks) / static_cast<double>(sysconf(_SC_CLK_TCK));
  }

  std::string out() const { return Slurp(out_path_); }
  std::string err() const { return err_path_.empty() ? out() : Slurp(err_path_); }
  /// What the process wrote (stdout, then stderr if it went elsewhere).
  std::string Log() const { return err_path_.empty() ? out() : out() + err(); }
  const std::filesystem::path& out_path() const { return out_path_; }
  const std::string& program() const { return argv_.front(); }

 private:
  static std::vector<std::string> Environment() {
    std::vector<std::string> environment;
    bool has_profile = false;
    for (char** e = environ; *e != nullptr; ++e) {
      environment.emplace_back(*e);
      has_profile = has_profile || environment.back().rfind("FASTRTPS_DEFAULT_PROFILES_FILE=", 0) == 0;
    }
#ifdef DPC_SOURCE_DIR
    if (!has_profile) {
      environment.push_back(std::string("FASTRTPS_DEFAULT_PROFILES_FILE=") + DPC_SOURCE_DIR +
                            "/deploy/fastdds/loopback.xml");
    }
#endif
    return environment;
  }
  bool Reap() {
    if (code_) return true;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) != pid_) return false;
    code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return true;
  }

  std::vector<std::string> argv_;
  std::filesystem::path out_path_, err_path_;
  pid_t pid_ = -1;
  std::optional<int> code_;
};

/// What a finished program did.
struct Result {
  int exit_code = -1;  ///< 128 + the signal if one ended it; -1 if it had to be stopped
  std::string out;
  std::string err;
};

/// Runs `argv` to completion, at most `timeout` (then it is stopped and exit_code is -1), with
/// its output in <directory>/<tag>.out and .err.
inline Result Run(std::vector<std::string> argv, const std::filesystem::path& directory, const std::string& tag,
                  std::chrono::milliseconds timeout = std::chrono::seconds(60)) {
  Process process(std::move(argv), directory / (tag + ".out"), directory / (tag + ".err"));
  const std::optional<int> code = process.Wait(timeout);
  if (!code) process.Stop();
  return Result{code.value_or(-1), process.out(), process.err()};
}

}  // namespace dpc::testing
