// The real instruments of a scenario (waveplate_device, polarimeter_device): how they are
// reached and spoken to. What comes from the operator's file is still checked: a command
// template that cannot be formatted, or would put a newline on the wire, is refused here rather
// than at the first command.

#include <arpa/inet.h>
#include <fmt/args.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <string>

#include "dpc/config/field_checks.h"
#include "dpc/config/scenario_validation.h"

namespace dpc {
namespace {

using field_checks::Fail;
using field_checks::RequirePositive;

constexpr std::array<int, 9> kBaudRates = {1200, 9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600};

void RequireLineText(const std::string& text, const std::string& path, bool may_be_empty) {
  if (text.empty() && !may_be_empty) Fail(path, "empty; the instrument needs a command");
  if (text.size() > kMaxInstrumentLineBytes) {
    Fail(path, fmt::format("{} bytes; at most {}", text.size(), kMaxInstrumentLineBytes));
  }
  for (const char c : text) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      Fail(path, "holds a control character (a line ends at \\n, which the link adds)");
    }
  }
}

void ValidateLink(const InstrumentLinkConfig& link, const std::string& path) {
  if (link.kind == InstrumentLinkConfig::Kind::kTcp) {
    in_addr address{};
    if (inet_pton(AF_INET, link.host.c_str(), &address) != 1) {
      Fail(path + ".tcp.host", fmt::format("\"{}\" is not an IPv4 address (no names: nothing is looked up)", link.host));
    }
    if (link.port < 1 || link.port > 65535) {
      Fail(path + ".tcp.port", fmt::format("{}: a TCP port is 1 to 65535 (give link {{ tcp {{ port: … }} }})", link.port));
    }
  } else {
    if (link.path.empty() || link.path.front() != '/' || link.path.size() > 255) {
      Fail(path + ".serial.path", fmt::format("\"{}\": an absolute device path of at most 255 bytes", link.path));
    }
    if (std::find(kBaudRates.begin(), kBaudRates.end(), link.baud) == kBaudRates.end()) {
      Fail(path + ".serial.baud", fmt::format("{}: one of 1200, 9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600",
                                              link.baud));
    }
  }
  RequirePositive(link.response_timeout_s, path + ".response_timeout_s", "a reply timeout in seconds must be > 0");
  if (link.response_timeout_s > 10.0) Fail(path + ".response_timeout_s", "at most 10 s");
  RequirePositive(link.reconnect_min_s, path + ".reconnect_min_s", "the first reconnection delay must be > 0");
  RequirePositive(link.reconnect_max_s, path + ".reconnect_max_s", "the longest reconnection delay must be > 0");
  if (link.reconnect_min_s > link.reconnect_max_s || link.reconnect_max_s > 600.0) {
    Fail(path + ".reconnect_max_s", fmt::format("{} s: at least reconnect_min_s ({} s) and at most 600 s",
                                                link.reconnect_max_s, link.reconnect_min_s));
  }
}

}  // namespace

std::string FormatSetCommand(const std::string& set_command, int channel, double volts, int64_t code) {
  fmt::dynamic_format_arg_store<fmt::format_context> args;
  args.push_back(fmt::arg("channel", channel));
  args.push_back(fmt::arg("volts", volts));
  args.push_back(fmt::arg("code", code));
  return fmt::vformat(set_command, args);
}

void ValidateWaveplateDevice(const WaveplateDeviceConfig& device, const std::vector<StageConfig>& stages) {
  const std::string path = "waveplate_device";
  ValidateLink(device.link, path + ".link");
  RequireLineText(device.set_command, path + ".set_command", false);
  if (device.set_command.find("{volts") == std::string::npos && device.set_command.find("{code") == std::string::npos) {
    Fail(path + ".set_command", "names neither {volts} nor {code}: it would not say what to set");
  }
  try {
    for (const double volts : {device.volts_min, device.volts_max}) {
      RequireLineText(FormatSetCommand(device.set_command, 1024, volts, int64_t{1} << 32), path + ".set_command",
                      false);
    }
  } catch (const fmt::format_error& e) {
    Fail(path + ".set_command", fmt::format("\"{}\" cannot be formatted ({}); the placeholders are {{channel}}, "
                                            "{{volts}} (e.g. {{volts:.4f}}) and {{code}}",
                                            device.set_command, e.what()));
  }
  RequireLineText(device.ack, path + ".ack", true);
  RequireLineText(device.read_command, path + ".read_command", true);
  if (!device.read_command.empty()) {
    if (device.read_command.find("{channel}") == std::string::npos) {
      Fail(path + ".read_command", "names no {channel}: it could not say which channel to read");
    }
    try {
      RequireLineText(FormatSetCommand(device.read_command, 1024, 0.0, 0), path + ".read_command", false);
    } catch (const fmt::format_error& e) {
      Fail(path + ".read_command", fmt::format("\"{}\" cannot be formatted ({})", device.read_command, e.what()));
    }
  }
  RequireLineText(device.identify, path + ".identify", true);
  const int controls = ScenarioControlCount(stages);
  if (!device.channels.empty()) {
    if (static_cast<int>(device.channels.size()) != controls) {
      Fail(path + ".channels", fmt::format("{} channels for {} controls: one per control, in order",
                                           device.channels.size(), controls));
    }
    std::set<int> seen;
    for (size_t i = 0; i < device.channels.size(); ++i) {
      const int channel = device.channels[i];
      if (channel < 1 || channel > 1024) Fail(fmt::format("{}.channels[{}]", path, i), "a channel is 1 to 1024");
      if (!seen.insert(channel).second) {
        Fail(fmt::format("{}.channels[{}]", path, i), fmt::format("channel {} is given twice", channel));
      }
    }
  }
  field_checks::RequireFinite(device.volts_min, path + ".volts_min", "the DAC's lowest voltage");
  field_checks::RequireFinite(device.volts_max, path + ".volts_max", "the DAC's highest voltage");
  if (!(device.volts_min < device.volts_max) || std::abs(device.volts_min) > 1e4 || std::abs(device.volts_max) > 1e4) {
    Fail(path + ".volts_max", fmt::format("[{}, {}] V: volts_min < volts_max, each within ±1e4 V", device.volts_min,
                                          device.volts_max));
  }
  if (device.dac_bits < 0 || device.dac_bits > 32) Fail(path + ".dac_bits", "0 (no quantization) to 32 bits");
  RequirePositive(device.max_slew_v_per_s, path + ".max_slew_v_per_s", "the device's slew limit must be > 0");
  field_checks::RequireNonNegative(device.settling_s, path + ".settling_s", "a settling time must be >= 0");
  if (device.settling_s > 10.0) Fail(path + ".settling_s", fmt::format("{} s: at most 10 s", device.settling_s));
  // No command may reach the device outside its full scale: every control needs a range
  // inside it (the calibrated range), which the driver clamps to.
  std::vector<std::pair<std::string, const std::optional<ControlRange>*>> ranges;
  CollectRanges(stages, &ranges);
  for (const auto& [range_path, range] : ranges) {
    if (!*range) {
      Fail(range_path, fmt::format("missing: a control driven by a waveplate device needs a range (volts) within "
                                   "its full scale [{}, {}]",
                                   device.volts_min, device.volts_max));
    }
    if ((*range)->min < device.volts_min || (*range)->max > device.volts_max) {
      Fail(range_path, fmt::format("[{}, {}] V reaches outside the device's full scale [{}, {}] V", (*range)->min,
                                   (*range)->max, device.volts_min, device.volts_max));
    }
  }
}

void ValidatePolarimeterDevice(const PolarimeterDeviceConfig& device) {
  const std::string path = "polarimeter_device";
  ValidateLink(device.link, path + ".link");
  RequireLineText(device.query, path + ".query", false);
  RequireLineText(device.stream_start, path + ".stream_start", true);
  if (!device.stream && !device.stream_start.empty()) {
    Fail(path + ".stream_start", "given without stream: true (it starts a stream that nothing would read)");
  }
  RequirePositive(device.min_dop, path + ".min_dop", "the lowest degree of polarization taken must be > 0");
  if (device.min_dop > 1.0) Fail(path + ".min_dop", fmt::format("{}: at most 1", device.min_dop));
}

}  // namespace dpc
