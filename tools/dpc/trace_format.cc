#include "trace_format.h"

#include <fmt/format.h>

#include <sstream>
#include <stdexcept>

#include "dpc/control/control_law_factory.h"
#include "trace_envelope.h"

namespace dpc::tools {
namespace {

constexpr const char* kMagic = "dpc-trace";

std::string Title(const ClosedLoopSimulator& simulator) {
  const ScenarioConfig& s = simulator.scenario();
  // The device in the paper's notation (M = M_m…M_1) and in the order the light meets it.
  return fmt::format("{}: M = {} (light: {}), {}, {} loop", s.name, simulator.chain().PaperNotation(),
                     simulator.chain().Describe(),
                     MethodName(s.controller.method),
                     s.controller.loop == LoopMode::kModel ? "model" : "measured");
}

}  // namespace

std::vector<std::string> TraceHeaderComments(const ClosedLoopSimulator& simulator,
                                             int64_t trace_every) {
  const ScenarioConfig& s = simulator.scenario();
  std::vector<std::string> lines{kMagic, "title=" + Title(simulator),
                                 fmt::format("activation_s={:.17g}", s.controller.activation_s)};
  if (simulator.target().is_point()) {
    const StokesVector& p = simulator.target().point();
    lines.push_back(fmt::format("target_point={:.17g},{:.17g},{:.17g}", p.x(), p.y(), p.z()));
  }
  if (simulator.chain().has_ranges()) {
    std::string ranges;
    const auto& lo = simulator.chain().range_min();
    const auto& hi = simulator.chain().range_max();
    for (size_t i = 0; i < lo.size(); ++i) ranges += fmt::format("{}{:.17g}:{:.17g}", i ? "," : "", lo[i], hi[i]);
    lines.push_back("control_ranges=" + ranges);
  }
  lines.push_back(fmt::format("sample_rate_hz={:.17g}", s.simulation.sample_rate_hz));
  lines.push_back(fmt::format("trace_every={}", trace_every));
  return lines;
}

FigureOptions FigureOptionsFor(const ClosedLoopSimulator& simulator) {
  FigureOptions options;
  options.title = Title(simulator);
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
    if (line == kMagic) {
      magic = true;
      continue;
    }
    const auto eq = line.find('=');
    if (eq != std::string::npos) metadata[line.substr(0, eq)] = line.substr(eq + 1);
  }
  if (!magic) {
    throw std::runtime_error(
        fmt::format("{} is not a dpc trace (no '# {}' line); write one with dpc sim --trace", path,
                    kMagic));
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
