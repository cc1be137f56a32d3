#pragma once
// The exit codes of every program of the project: the `dpc` command and the bench's services.

namespace dpc::cli {

enum class ExitCode : int {
  kOk = 0,
  kRuntimeError = 1,         ///< failed while running: I/O, plotting, no answer in time
  kInvalidInput = 2,         ///< bad command line, invalid scenario or configuration, refused request
  kNoData = 3,               ///< dpc topic echo / hz: nothing arrived within --timeout-s
  kInitializationError = 4,  ///< could not start: DDS profiles or participant, the device
  kInterrupted = 130,        ///< dpc sim / sweep stopped by SIGINT/SIGTERM; partial results shown
};

/// The process exit status of `code`.
constexpr int ToInt(ExitCode code) { return static_cast<int>(code); }

}  // namespace dpc::cli
