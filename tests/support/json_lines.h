#pragma once
// The JSON report a service or `dpc` printed: the last line of a log that starts with '{'.

#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

namespace dpc::testing {

/// The last line of `log` that starts with '{', parsed; a null json if there is none or it does
/// not parse (the caller checks is_object()).
inline nlohmann::json LastJsonLine(const std::string& log) {
  std::istringstream in(log);
  std::string line, last;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '{') last = line;
  }
  return last.empty() ? nlohmann::json() : nlohmann::json::parse(last, nullptr, false);
}

}  // namespace dpc::testing
