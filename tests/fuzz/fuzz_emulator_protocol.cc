// dpc-emulator's protocol core (services/emulator/emulator_core.h) on any bytes from a client
// of the EPC, the polarimeter or the control port: it never crashes, throws or grows its output
// without bound (a client that does not read is cut at its queue's bound), and the optics it
// reports stay finite and unit.
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>

#include "dpc/config/scenario_config.h"
#include "emulator_core.h"
#include "fuzz_support.h"

namespace {

dpc::ScenarioConfig Device() {
  dpc::ScenarioConfig scenario = dpc::PaperScenario("131");
  for (dpc::StageConfig& stage : scenario.stages) stage.range = dpc::ControlRange{-10.0, 10.0};
  scenario.simulation.sample_rate_hz = 1e4;  // the input's steps: one sample of delay, one of dither reset
  scenario.simulation.delay_s = 1e-4;
  scenario.controller.dither.reset_duration_s = 1e-4;
  scenario.simulation.duration_s = 1.0;
  scenario.input.disturbances[0].rate_rad_per_s = 20.0;
  return scenario;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  using dpc::services::EmulatorCore;
  using dpc::services::Instrument;
  static const dpc::ScenarioConfig scenario = Device();
  EmulatorCore core(scenario, dpc::services::EmulatorSettings{}, 0);
  const Instrument instrument = data[0] % 3 == 0 ? Instrument::kEpc
                                : data[0] % 3 == 1 ? Instrument::kPolarimeter
                                                   : Instrument::kControl;
  const auto session = core.Open(instrument, 0);
  DPC_FUZZ_CHECK(session.has_value(), "contract", "a fresh emulator refused its first client");
  // The bytes arrive in pieces (a split at every byte whose low bits say so), at growing times.
  int64_t now_ns = 0;
  size_t start = 1;
  for (size_t k = 1; k <= size; ++k) {
    if (k == size || (data[k] & 0x0f) == 0) {
      now_ns += 1'000'000;
      core.Receive(*session, std::string_view(reinterpret_cast<const char*>(data + start), k - start), now_ns);
      start = k;
      if (core.IsOpen(*session)) {
        const std::string_view out = core.Output(*session, now_ns);
        DPC_FUZZ_CHECK(out.size() <= (1u << 17), "out-of-range", "%zu bytes queued for one client", out.size());
        core.Written(*session, out.size());
      }
    }
  }
  const auto status = core.Status(now_ns);
  for (const char* key : {"s_in", "s_out"}) {
    double norm = 0.0;
    for (const auto& v : status[key]) norm += v.get<double>() * v.get<double>();
    DPC_FUZZ_CHECK(std::isfinite(norm) && std::abs(std::sqrt(norm) - 1.0) < 1e-6, "out-of-range",
                   "the emulator's %s is not unit", key);
  }
  return 0;
}
