#pragma once
// Exit codes of the dpc tool.

namespace dpc::tools {

inline constexpr int kExitOk = 0;
inline constexpr int kExitRuntimeError = 1;    ///< I/O, plotting or another failure while running
inline constexpr int kExitInvalidInput = 2;    ///< bad command line or invalid scenario
inline constexpr int kExitInterrupted = 130;   ///< stopped by SIGINT/SIGTERM; partial results shown

}  // namespace dpc::tools
