// Writes the MCAP files the reference-reader test reads: one per compression (none, zstd, lz4)
// in DIR, and DIR/expected.json with what each file must hold (schemas, channels, metadata,
// every message with its payload in hex), for tests/mcap/read_with_mcap_core.mjs.
//
//   dpc_mcap_sample DIR
#include <cstdio>
#include <fstream>
#include <string>

#include <fmt/format.h>

#include "dpc/record/mcap.h"

using namespace dpc::record;

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: dpc_mcap_sample DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  std::string messages;
  for (const McapCompression compression : {McapCompression::kNone, McapCompression::kZstd, McapCompression::kLz4}) {
    const std::string name = *McapCompressionName(compression) ? McapCompressionName(compression) : "none";
    McapWriter writer(dir + "/sample-" + name + ".mcap", {"jacobian-dpc sample", compression, 4096});
    const uint16_t sample = writer.AddSchema("dpc::msg::StokesSample", "omgidl", "module dpc { module msg { struct StokesSample { double s1; }; }; };");
    const uint16_t state = writer.AddSchema("dpc::msg::WaveplateState", "omgidl", "module dpc { module msg { struct WaveplateState { long mode; }; }; };");
    const uint16_t channels[] = {writer.AddChannel(sample, "dpc_stokes_sample", "cdr", {{"partition", "dpc.bench1"}}),
                                 writer.AddChannel(state, "dpc_waveplate_state", "cdr")};
    writer.WriteMetadata({"scenario", {{"text", "name: \"sample\"\n"}}});
    writer.WriteMetadata({"recorder", {{"version", "test"}, {"host", "here"}}});
    messages.clear();
    for (int k = 0; k < 2000; ++k) {
      McapMessage m;
      m.channel_id = channels[k % 2];
      m.sequence = static_cast<uint32_t>(k + 1);
      m.log_time_ns = 1'700'000'000'000'000'000ull + static_cast<uint64_t>(k) * 100'000;
      m.publish_time_ns = m.log_time_ns - 30'000;
      std::string hex;
      for (int i = 0; i < 16 + k % 41; ++i) {
        const auto byte = static_cast<unsigned char>((k * 13 + i * 7) & 0xFF);
        m.data.push_back(static_cast<char>(byte));
        hex += fmt::format("{:02x}", byte);
      }
      writer.Write(m);
      messages += fmt::format("{}{{\"topic\":\"{}\",\"sequence\":{},\"log_time\":\"{}\",\"publish_time\":\"{}\",\"data\":\"{}\"}}",
                              messages.empty() ? "" : ",\n", k % 2 ? "dpc_waveplate_state" : "dpc_stokes_sample",
                              m.sequence, m.log_time_ns, m.publish_time_ns, hex);
    }
    writer.Close();
  }
  std::ofstream out(dir + "/expected.json");
  out << "{\"files\":[\"sample-none.mcap\",\"sample-zstd.mcap\",\"sample-lz4.mcap\"],\n"
      << "\"library\":\"jacobian-dpc sample\",\n"
      << "\"schemas\":{\"dpc_stokes_sample\":\"dpc::msg::StokesSample\",\"dpc_waveplate_state\":\"dpc::msg::WaveplateState\"},\n"
      << "\"metadata\":{\"scenario\":{\"text\":\"name: \\\"sample\\\"\\n\"},\"recorder\":{\"version\":\"test\",\"host\":\"here\"}},\n"
      << "\"messages\":[\n" << messages << "]}\n";
  return out ? 0 : 1;
}
