#pragma once
// A program `dpc` starts and stops (dpc evaluate runs a bench of processes): posix_spawnp in a
// process group of its own (a terminal's Ctrl-C reaches dpc alone, which stops its children in
// order, and a controller given as a shell command is stopped with whatever it started), its
// output into files, the signals dpc catches or ignores back to their defaults.

#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

namespace dpc::tools {

class ChildProcess {
 public:
  /// Starts `argv` (argv[0] searched in PATH) with standard output into `out_path` and standard
  /// error into `err_path` (created or truncated), the environment without the variables named
  /// in `unset` and with `extra_env` ("NAME=value"). Throws std::runtime_error naming the
  /// program if it cannot be started.
  ChildProcess(const std::vector<std::string>& argv, const std::string& out_path, const std::string& err_path,
               const std::vector<std::string>& extra_env = {}, const std::vector<std::string>& unset = {});
  /// Stop()s it if it still runs.
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  /// Its wait status once it has ended (without waiting); nullopt while it runs.
  std::optional<int> Poll();
  /// SIGTERM to its process group, up to `grace_s` for it to end, then SIGKILL. Its wait status.
  int Stop(double grace_s = 5.0);

  /// "exit 0", "exit 2", "killed by signal 9".
  static std::string DescribeStatus(int wait_status);

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
};

}  // namespace dpc::tools
