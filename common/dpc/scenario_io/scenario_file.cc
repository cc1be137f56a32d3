#include "dpc/scenario_io/scenario_file.h"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "dpc/config/scenario_validation.h"
#include "dpc/scenario_io/scenario_reader.h"

namespace dpc {

std::string ReadScenarioText(const std::string& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (std::filesystem::is_directory(status)) {
    throw ScenarioError(path, "is a directory; expected a scenario file (.pbtxt)");
  }
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
    // A FIFO or a device would block the reader (a service at start-up) or never end.
    throw ScenarioError(path, "is not a regular file (a pipe, socket or device); expected a scenario file (.pbtxt)");
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    throw ScenarioError(path, fmt::format("cannot open the scenario file: {}",
                                          std::strerror(errno)));
  }
  std::string text;
  char buffer[1 << 16];
  while (file.read(buffer, sizeof buffer) || file.gcount() > 0) {
    text.append(buffer, static_cast<size_t>(file.gcount()));
    if (text.size() > kMaxScenarioTextBytes) {
      throw ScenarioError(path, fmt::format("the scenario file is larger than {} bytes (16 MiB); "
                                            "a scenario is a small text file",
                                            kMaxScenarioTextBytes));
    }
  }
  if (file.bad()) {
    throw ScenarioError(path, fmt::format("cannot read the scenario file: {}",
                                          std::strerror(errno)));
  }
  return text;
}

ScenarioConfig ReadScenarioFile(const std::string& path) {
  return ScenarioFromProto(ParseScenarioText(ReadScenarioText(path), path));
}

ScenarioConfig LoadScenarioFile(const std::string& path) {
  ScenarioConfig config = ReadScenarioFile(path);
  ValidateScenario(config);
  return config;
}

}  // namespace dpc
