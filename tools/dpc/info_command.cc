#include "info_command.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <iostream>

namespace dpc::tools {

RecordingInfo InspectRecording(const std::string& path) {
  RecordingInfo info;
  std::error_code error;
  info.bytes = std::filesystem::file_size(path, error);
  if (error) throw std::runtime_error(fmt::format("cannot read {}: {}", path, error.message()));
  info.first_ns = UINT64_MAX;
  info.read = record::ReadMcap(path, [&](const record::McapChannel& channel, const record::McapMessage& m) {
    ChannelInfo& c = info.channels[channel.id];
    if (c.messages == 0) {
      c.first_ns = m.log_time_ns;
    } else if (m.log_time_ns > c.last_ns && m.log_time_ns - c.last_ns > c.largest_gap_ns) {
      c.largest_gap_ns = m.log_time_ns - c.last_ns;
      c.largest_gap_at_ns = m.log_time_ns;
    }
    c.last_ns = std::max(c.last_ns, m.log_time_ns);
    ++c.messages;
    info.first_ns = std::min(info.first_ns, m.log_time_ns);
    info.last_ns = std::max(info.last_ns, m.log_time_ns);
  });
  if (info.first_ns == UINT64_MAX) info.first_ns = 0;
  for (const auto& [id, channel] : info.read.channels) {
    ChannelInfo& c = info.channels[id];
    c.topic = channel.topic;
    c.encoding = channel.message_encoding;
    const auto schema = info.read.schemas.find(channel.schema_id);
    c.schema = schema == info.read.schemas.end() ? "" : schema->second.name;
  }
  return info;
}

namespace {

double Seconds(uint64_t ns) { return static_cast<double>(ns) * 1e-9; }

double RateHz(const ChannelInfo& c) {
  return c.messages > 1 && c.last_ns > c.first_ns ? static_cast<double>(c.messages - 1) / Seconds(c.last_ns - c.first_ns)
                                                   : 0.0;
}

}  // namespace

std::string RecordingInfoText(const std::string& path, const RecordingInfo& info) {
  const auto& r = info.read;
  std::string text = fmt::format("file       {} ({:.3f} MB), written by {}\n", path, static_cast<double>(info.bytes) / 1e6,
                                 r.library.empty() ? "?" : r.library);
  text += r.complete ? std::string("state      complete (data end, summary and footer read, CRCs checked)\n")
                     : fmt::format("state      NOT complete: {}; what is before it was read\n", r.problem);
  text += fmt::format("duration   {:.3f} s\n", info.last_ns > info.first_ns ? Seconds(info.last_ns - info.first_ns) : 0.0);
  text += fmt::format("messages   {} in {} chunks, {} channels, {} schemas\n", r.messages, r.chunks, r.channels.size(),
                      r.schemas.size());
  std::string names;
  for (const auto& m : r.metadata) names += (names.empty() ? "" : ", ") + m.name;
  text += fmt::format("metadata   {}\n", names.empty() ? "none" : names);
  text += fmt::format("{:>4}  {:<28} {:<30} {:>10} {:>10} {:>14}\n", "id", "topic", "schema", "messages", "rate_hz",
                      "largest_gap_ms");
  for (const auto& [id, c] : info.channels) {
    text += fmt::format("{:>4}  {:<28} {:<30} {:>10} {:>10.1f} {:>14.3f}\n", id, c.topic, c.schema, c.messages,
                        RateHz(c), static_cast<double>(c.largest_gap_ns) * 1e-6);
  }
  return text;
}

CLI::App* AddInfoCommand(CLI::App& app, InfoOptions* o) {
  CLI::App* info = app.add_subcommand("info", "What a recording (MCAP) holds: topics, counts, duration, rates, gaps");
  info->add_option("file", o->path, "The MCAP file")->required()->check(CLI::ExistingFile);
  info->add_flag("--json", o->json, "Print one JSON object");
  return info;
}

cli::ExitCode RunInfoCommand(const InfoOptions& o) {
  RecordingInfo info;
  try {
    info = InspectRecording(o.path);
  } catch (const std::exception& e) {
    fmt::print(stderr, "dpc info: {}\n", e.what());
    return cli::ExitCode::kInvalidInput;
  }
  if (o.json) {
    nlohmann::ordered_json j;
    j["file"] = o.path;
    j["bytes"] = info.bytes;
    j["library"] = info.read.library;
    j["complete"] = info.read.complete;
    j["problem"] = info.read.problem;
    j["duration_s"] = info.last_ns > info.first_ns ? Seconds(info.last_ns - info.first_ns) : 0.0;
    j["messages"] = info.read.messages;
    j["chunks"] = info.read.chunks;
    nlohmann::ordered_json metadata = nlohmann::ordered_json::object();
    for (const auto& m : info.read.metadata) metadata[m.name] = m.values;
    j["metadata"] = metadata;
    nlohmann::ordered_json channels = nlohmann::ordered_json::array();
    for (const auto& [id, c] : info.channels) {
      channels.push_back({{"id", id}, {"topic", c.topic}, {"schema", c.schema}, {"message_encoding", c.encoding},
                          {"messages", c.messages}, {"rate_hz", RateHz(c)},
                          {"largest_gap_s", Seconds(c.largest_gap_ns)},
                          {"largest_gap_ends_at_s", c.largest_gap_ns ? Seconds(c.largest_gap_at_ns - info.first_ns) : 0.0}});
    }
    j["channels"] = channels;
    std::cout << j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << std::endl;
  } else {
    fmt::print("{}", RecordingInfoText(o.path, info));
  }
  // A recording cut short is still read; say so in the exit code for scripts.
  return info.read.complete ? cli::ExitCode::kOk : cli::ExitCode::kRuntimeError;
}

}  // namespace dpc::tools
