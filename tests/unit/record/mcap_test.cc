#include "dpc/record/mcap.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace dpc::record {
namespace {

class McapTest : public ::testing::TestWithParam<McapCompression> {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("dpc_mcap_test_" + std::to_string(::getpid()) + "_" +
                  std::to_string(reinterpret_cast<uintptr_t>(this)));
    std::filesystem::create_directories(directory_);
    path_ = (directory_ / "run.mcap").string();
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  // Two channels of one schema and one of another; `count` messages alternating between them,
  // payloads of varying length (bytes 0…255, so that any byte value goes through).
  std::vector<McapMessage> WriteSample(McapWriter* writer, int count) {
    const uint16_t sample = writer->AddSchema("dpc::msg::StokesSample", "omgidl", "module dpc { struct S { double x; }; };");
    const uint16_t state = writer->AddSchema("dpc::msg::WaveplateState", "omgidl", "module dpc { struct W { long y; }; };");
    const uint16_t a = writer->AddChannel(sample, "dpc_stokes_sample", "cdr", {{"partition", "dpc.bench1"}});
    const uint16_t b = writer->AddChannel(state, "dpc_waveplate_state", "cdr");
    const uint16_t c = writer->AddChannel(0, "schemaless", "json");
    writer->WriteMetadata({"scenario", {{"text", "name: \"x\"\n"}, {"version", "1"}}});
    std::vector<McapMessage> written;
    for (int k = 0; k < count; ++k) {
      McapMessage m;
      m.channel_id = k % 5 == 4 ? c : (k % 2 ? b : a);
      m.sequence = static_cast<uint32_t>(k);
      m.log_time_ns = 1'700'000'000'000'000'000ull + static_cast<uint64_t>(k) * 100'000;
      m.publish_time_ns = m.log_time_ns - 40'000;
      for (int i = 0; i < 20 + k % 37; ++i) m.data.push_back(static_cast<char>((k * 7 + i) & 0xFF));
      writer->Write(m);
      written.push_back(m);
    }
    return written;
  }

  std::filesystem::path directory_;
  std::string path_;
};

TEST_P(McapTest, WhatIsWrittenReadsBackInOrderWithItsChannelsSchemasAndMetadata) {
  std::vector<McapMessage> written;
  {
    McapWriter writer(path_, {"jacobian-dpc test", GetParam(), 4096});
    written = WriteSample(&writer, 1000);
    writer.Close();
    EXPECT_EQ(writer.messages(), 1000u);
    EXPECT_GT(writer.chunks(), 5u) << "4-KiB chunks";
  }
  std::vector<McapMessage> read;
  std::vector<std::string> topics;
  const McapReadResult result = ReadMcap(path_, [&](const McapChannel& channel, const McapMessage& m) {
    read.push_back(m);
    topics.push_back(channel.topic);
  });
  EXPECT_EQ(result.problem, "");
  EXPECT_TRUE(result.data_end);
  EXPECT_TRUE(result.complete);
  EXPECT_EQ(result.library, "jacobian-dpc test");
  ASSERT_EQ(read.size(), written.size());
  for (size_t k = 0; k < read.size(); ++k) {
    EXPECT_EQ(read[k].channel_id, written[k].channel_id) << k;
    EXPECT_EQ(read[k].sequence, written[k].sequence) << k;
    EXPECT_EQ(read[k].log_time_ns, written[k].log_time_ns) << k;
    EXPECT_EQ(read[k].publish_time_ns, written[k].publish_time_ns) << k;
    ASSERT_EQ(read[k].data, written[k].data) << k;
  }
  EXPECT_EQ(topics[0], "dpc_stokes_sample");
  EXPECT_EQ(topics[1], "dpc_waveplate_state");
  ASSERT_EQ(result.schemas.size(), 2u);
  EXPECT_EQ(result.schemas.at(1).name, "dpc::msg::StokesSample");
  EXPECT_EQ(result.schemas.at(2).encoding, "omgidl");
  ASSERT_EQ(result.channels.size(), 3u);
  EXPECT_EQ(result.channels.at(0).metadata.at("partition"), "dpc.bench1");
  EXPECT_EQ(result.channels.at(2).schema_id, 0);
  ASSERT_EQ(result.metadata.size(), 1u);
  EXPECT_EQ(result.metadata[0].values.at("text"), "name: \"x\"\n");

  const auto summary = ReadMcapSummary(path_);
  ASSERT_TRUE(summary.has_value());
  EXPECT_EQ(summary->message_count, 1000u);
  EXPECT_EQ(summary->chunk_count, result.chunks);
  EXPECT_EQ(summary->chunk_indexes, result.chunks);
  EXPECT_EQ(summary->channels.size(), 3u);
  EXPECT_EQ(summary->schemas.size(), 2u);
  EXPECT_EQ(summary->message_start_time, written.front().log_time_ns);
  EXPECT_EQ(summary->message_end_time, written.back().log_time_ns);
  EXPECT_EQ(summary->channel_message_counts.at(2), 200u);
}

TEST_P(McapTest, AFileCutAnywhereKeepsEveryRecordBeforeTheCut) {
  // A recorder killed with -9: the file ends anywhere. Every message of a complete chunk before
  // the cut is read back, nothing after it, and the reader says where it stopped.
  std::vector<McapMessage> written;
  {
    McapWriter writer(path_, {"test", GetParam(), 2048});
    written = WriteSample(&writer, 400);
    writer.Close();
  }
  const auto size = std::filesystem::file_size(path_);
  std::string bytes(size, '\0');
  std::ifstream(path_, std::ios::binary).read(bytes.data(), static_cast<std::streamsize>(size));
  const std::string cut_path = (directory_ / "cut.mcap").string();
  size_t previous = 0;
  for (size_t cut = 40; cut < size; cut += 97) {
    std::ofstream(cut_path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(cut));
    size_t n = 0;
    const McapReadResult result = ReadMcap(cut_path, [&](const McapChannel&, const McapMessage& m) {
      ASSERT_LT(n, written.size());
      EXPECT_EQ(m.data, written[n].data);
      ++n;
    });
    EXPECT_FALSE(result.complete) << cut;
    EXPECT_NE(result.problem, "") << cut;
    EXPECT_GE(n, previous) << "a longer prefix never reads fewer messages (cut at " << cut << ")";
    previous = n;
    EXPECT_FALSE(ReadMcapSummary(cut_path).has_value());
  }
  EXPECT_GT(previous, 300u) << "most chunks lie before the last cut";
}

TEST_P(McapTest, FlushWritesTheChunkBeingFilled) {
  McapWriter writer(path_, {"test", GetParam(), 1 << 20});
  WriteSample(&writer, 10);
  writer.Flush();
  // The file is not closed (a recording in progress), yet what was flushed reads back.
  size_t n = 0;
  const McapReadResult result = ReadMcap(path_, [&](const McapChannel&, const McapMessage&) { ++n; });
  EXPECT_EQ(n, 10u);
  EXPECT_FALSE(result.data_end);
  writer.Close();
}

TEST_P(McapTest, InLogTimeOrderMessagesOutOfOrderWithinTheWindowComeBackInOrder) {
  // Drain-order files: per 20-ms batch, channel a's messages, then b's; a's log times interleave
  // with b's. Log times are whole microseconds; a few are equal across channels.
  std::vector<uint64_t> log_times;
  {
    McapWriter writer(path_, {"jacobian-dpc test", GetParam(), 4096});
    const uint16_t a = writer.AddChannel(0, "a", "cdr");
    const uint16_t b = writer.AddChannel(0, "b", "cdr");
    uint32_t sequence = 0;
    for (int batch = 0; batch < 50; ++batch) {
      const uint64_t start_ns = 1'000'000'000ull + static_cast<uint64_t>(batch) * 20'000'000;
      for (const uint16_t channel : {a, b}) {
        for (int k = 0; k < 40; ++k) {
          const uint64_t t = start_ns + static_cast<uint64_t>(k) * 500'000 + (channel == b ? 250'000 * (k % 2) : 0);
          writer.Write({channel, ++sequence, t, t, std::string(1, static_cast<char>(k))});
          log_times.push_back(t);
        }
      }
    }
    writer.Close();
  }
  std::vector<uint64_t> delivered;
  std::vector<uint32_t> sequences;
  const McapReadResult r = ReadMcapInLogTimeOrder(path_, 25'000'000, [&](const McapChannel&, const McapMessage& m) {
    delivered.push_back(m.log_time_ns);
    sequences.push_back(m.sequence);
  });
  EXPECT_TRUE(r.complete) << r.problem;
  std::vector<uint64_t> sorted = log_times;
  std::stable_sort(sorted.begin(), sorted.end());
  EXPECT_EQ(delivered, sorted);
  // Equal log times keep their file order (channel a's, written first, before b's).
  for (size_t i = 1; i < delivered.size(); ++i) {
    if (delivered[i] == delivered[i - 1]) {
      EXPECT_LT(sequences[i - 1], sequences[i]);
    }
  }
  // A window shorter than the disorder does not sort it all (and loses nothing).
  delivered.clear();
  ReadMcapInLogTimeOrder(path_, 1'000'000, [&](const McapChannel&, const McapMessage& m) { delivered.push_back(m.log_time_ns); });
  EXPECT_EQ(delivered.size(), log_times.size());
  EXPECT_FALSE(std::is_sorted(delivered.begin(), delivered.end()));
}

INSTANTIATE_TEST_SUITE_P(Compressions, McapTest,
                         ::testing::Values(McapCompression::kNone, McapCompression::kZstd, McapCompression::kLz4),
                         [](const auto& info) {
                           const std::string name = McapCompressionName(info.param);
                           return name.empty() ? std::string("none") : name;
                         });

TEST(McapFileTest, CorruptionIsReportedNotThrownAndMisuseIsRefused) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("dpc_mcap_corrupt_" + std::to_string(::getpid()) + ".mcap")).string();
  {
    McapWriter writer(path, {"test", McapCompression::kZstd, 1 << 20});
    const uint16_t schema = writer.AddSchema("s", "omgidl", "x");
    const uint16_t channel = writer.AddChannel(schema, "t", "cdr");
    EXPECT_THROW(writer.AddChannel(7, "t", "cdr"), std::invalid_argument);
    McapMessage m;
    m.channel_id = 9;
    EXPECT_THROW(writer.Write(m), std::invalid_argument);
    m.channel_id = channel;
    m.data = std::string(5000, 'a');
    writer.Write(m);
    writer.Close();
    EXPECT_THROW(writer.Write(m), std::runtime_error);
  }
  // Flip a byte inside the chunk's compressed records.
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const size_t chunk = bytes.find(std::string("zstd"));
  ASSERT_NE(chunk, std::string::npos);
  bytes[chunk + 4 + 8 + 10] ^= 0x5A;
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
  size_t n = 0;
  const McapReadResult result = ReadMcap(path, [&](const McapChannel&, const McapMessage&) { ++n; });
  EXPECT_EQ(n, 0u);
  EXPECT_NE(result.problem.find("chunk"), std::string::npos) << result.problem;
  // Not MCAP at all.
  std::ofstream(path, std::ios::binary | std::ios::trunc) << "t_s,s1\n0,1\n";
  EXPECT_THROW(ReadMcap(path, [](const McapChannel&, const McapMessage&) {}), std::runtime_error);
  std::filesystem::remove(path);
  EXPECT_THROW(ParseMcapCompression("gzip"), std::invalid_argument);
  EXPECT_EQ(ParseMcapCompression("lz4"), McapCompression::kLz4);
}

}  // namespace
}  // namespace dpc::record
