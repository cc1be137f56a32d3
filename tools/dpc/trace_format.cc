#include "trace_format.h"

#include <fmt/format.h>

#include <sstream>
#include <stdexcept>

#include "dpc/control/control_law_factory.h"
#include "dpc/sim/trace_header.h"
#include "trace_envelope.h"

namespace dpc::tools {

std::vector<std::string> TraceHeaderComments(const ClosedLoopSimulator& simulator, int64_t trace_every) {
  return TraceHeaderLines(simulator.scenario(), simulator.chain(), simulator.target(), trace_every);
}

FigureOptions FigureOptionsFor(const ClosedLoopSimulator& simulator) {
  FigureOptions options;
  options.title = TraceTitle(simulator.scenario(), simulator.chain());
  options.activation_s = simulator.scenario().controller.activation_s;
  if (simulator.target().is_point()) options.target_point = simulator.target().point();
  if (simulator.chain().has_ranges()) {
    const auto& lo = simulator.chain().range_min();
    const auto& hi = simulator.chain().range_max();
    for (size_t i = 0; i < lo.size(); ++i) options.control_ranges.emplace_back(lo[i], hi[i]);
  }
  return options;
}

std::map<std::string, std::string> ReadTraceMetadata(const std::string& path) {
  const TraceHeader header = ReadTraceHeader(path);
  std::map<std::string, std::string> metadata;
  bool magic = false;
  for (const std::string& line : header.comment_lines) {
    if (line == kTraceMagic) {
      magic = true;
      continue;
    }
    const auto eq = line.find('=');
    if (eq != std::string::npos) metadata[line.substr(0, eq)] = line.substr(eq + 1);
  }
  if (!magic) {
    throw std::runtime_error(
        fmt::format("{} is not a dpc trace (no '# {}' line); write one with dpc sim --trace", path,
                    kTraceMagic));
  }
  return metadata;
}

FigureOptions FigureOptionsFromMetadata(const std::map<std::string, std::string>& metadata) {
  FigureOptions options;
  if (auto it = metadata.find("title"); it != metadata.end()) options.title = it->second;
  if (auto it = metadata.find("activation_s"); it != metadata.end()) {
    options.activation_s = std::stod(it->second);
  }
  if (auto it = metadata.find("target_point"); it != metadata.end()) {
    std::stringstream ss(it->second);
    std::string part;
    std::vector<double> values;
    while (std::getline(ss, part, ',')) values.push_back(std::stod(part));
    if (values.size() == 3) options.target_point = StokesVector(values[0], values[1], values[2]);
  }
  if (auto it = metadata.find("control_ranges"); it != metadata.end()) {
    std::stringstream ss(it->second);
    std::string part;
    while (std::getline(ss, part, ',')) {
      const auto colon = part.find(':');
      if (colon == std::string::npos) {
        throw std::runtime_error(fmt::format("trace metadata control_ranges: '{}' is not min:max", part));
      }
      options.control_ranges.emplace_back(std::stod(part.substr(0, colon)), std::stod(part.substr(colon + 1)));
    }
  }
  return options;
}

}  // namespace dpc::tools
