#include "dpc/sim/trace_header.h"

#include <fmt/format.h>

#include "dpc/control/control_law_factory.h"

namespace dpc {

std::string TraceTitle(const ScenarioConfig& s, const WaveplateChain& chain) {
  // The device in the paper's notation (M = M_m…M_1) and in the order the light meets it.
  return fmt::format("{}: M = {} (light: {}), {}, {} loop", s.name, chain.PaperNotation(), chain.Describe(),
                     MethodName(s.controller.method), s.controller.loop == LoopMode::kModel ? "model" : "measured");
}

std::vector<std::string> TraceHeaderLines(const ScenarioConfig& s, const WaveplateChain& chain, const Target& target,
                                          int64_t trace_every, const std::string& producer) {
  std::vector<std::string> lines{kTraceMagic, "title=" + TraceTitle(s, chain),
                                 fmt::format("activation_s={:.17g}", s.controller.activation_s)};
  if (!producer.empty()) lines.push_back("producer=" + producer);
  if (target.is_point()) {
    const StokesVector& p = target.point();
    lines.push_back(fmt::format("target_point={:.17g},{:.17g},{:.17g}", p.x(), p.y(), p.z()));
  }
  if (chain.has_ranges()) {
    std::string ranges;
    const auto& lo = chain.range_min();
    const auto& hi = chain.range_max();
    for (size_t i = 0; i < lo.size(); ++i) ranges += fmt::format("{}{:.17g}:{:.17g}", i ? "," : "", lo[i], hi[i]);
    lines.push_back("control_ranges=" + ranges);
  }
  lines.push_back(fmt::format("sample_rate_hz={:.17g}", s.simulation.sample_rate_hz));
  lines.push_back(fmt::format("trace_every={}", trace_every));
  return lines;
}

}  // namespace dpc
