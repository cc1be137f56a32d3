#pragma once
// MCAP files (the public specification at mcap.dev, version 0): the container the bench's
// recordings are kept in, readable by the MCAP tools (Foxglove, `mcap`, @mcap/core).
//
// McapWriter writes, in this order:
//   magic, Header(profile "", library "jacobian-dpc <version>")
//   data section: each Schema and Channel record when it is added (before any message that
//     uses it), Metadata records, and the messages in Chunks (compressed with zstd or lz4 or not
//     at all; CRC32 of the uncompressed records), each chunk followed by one MessageIndex
//     record per channel it holds (log time, offset in the chunk's records)
//   DataEnd (CRC32 of the data section)
//   summary: Schemas, Channels, Statistics, MetadataIndexes, ChunkIndexes, one SummaryOffset
//     per group
//   Footer (summary start, summary offset start, CRC32 of the summary), magic
// so that an indexed reader seeks by the chunk indexes, and a streaming reader reads the file
// from the start. A chunk is written when its records reach chunk_size_bytes and by Flush():
// a crash (kill -9) loses at most the chunk being filled, and ReadMcap recovers every complete
// record before the break.
//
// ReadMcap reads a file from its start (records, chunks decompressed, their CRC checked), and
// stops at the end of the data section or at the first incomplete or corrupt record (reported,
// not thrown: the records before it are kept). A chunk of more than 256 MiB uncompressed is
// refused. ReadMcapSummary reads the summary section by the footer, without the data.
//
// Not for the real-time path: files, compression, allocation.

#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dpc::record {

enum class McapCompression { kNone, kZstd, kLz4 };

/// "", "zstd", "lz4" (the names MCAP stores). Throws std::invalid_argument for another name.
McapCompression ParseMcapCompression(const std::string& name);
const char* McapCompressionName(McapCompression compression);

struct McapSchema {
  uint16_t id = 0;
  std::string name;      ///< e.g. "dpc::msg::StokesSample"
  std::string encoding;  ///< e.g. "omgidl"
  std::string data;      ///< e.g. the IDL text
};

struct McapChannel {
  uint16_t id = 0;
  uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;  ///< e.g. "cdr"
  std::map<std::string, std::string> metadata;
};

struct McapMessage {
  uint16_t channel_id = 0;
  uint32_t sequence = 0;
  uint64_t log_time_ns = 0;      ///< when the recorder received it
  uint64_t publish_time_ns = 0;  ///< when its writer published it
  std::string data;              ///< the payload, bytes as they arrived
};

struct McapMetadata {
  std::string name;
  std::map<std::string, std::string> values;
};

struct McapWriterOptions {
  std::string library = "jacobian-dpc";
  McapCompression compression = McapCompression::kZstd;
  size_t chunk_size_bytes = 1 << 20;  ///< uncompressed records per chunk before it is written
};

class McapWriter {
 public:
  /// Creates (truncates) `path` and writes the magic and the header. Throws std::runtime_error.
  McapWriter(const std::string& path, McapWriterOptions options);
  /// Closes the file properly if Close() was not called (errors are swallowed there).
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// Returns the new schema's id (1, 2, …). Throws std::runtime_error after Close or on a
  /// write error, std::length_error past 65535 schemas.
  uint16_t AddSchema(const std::string& name, const std::string& encoding, const std::string& data);
  /// Returns the new channel's id (0, 1, …); `schema_id` must be one AddSchema returned (or 0:
  /// none). Throws std::invalid_argument for an unknown schema.
  uint16_t AddChannel(uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                      const std::map<std::string, std::string>& metadata = {});
  /// Appends a message of a channel AddChannel returned (std::invalid_argument otherwise) to the
  /// chunk being filled; writes the chunk when it is full.
  void Write(const McapMessage& message);
  void WriteMetadata(const McapMetadata& metadata);
  /// Writes the chunk being filled (if any) and flushes the file to the operating system.
  void Flush();
  /// The last chunk, the data end, the summary, the footer. Throws std::runtime_error on a
  /// write error. Idempotent.
  void Close();

  uint64_t messages() const { return message_count_; }
  uint64_t chunks() const { return chunk_count_; }
  /// Bytes written to the file so far.
  uint64_t bytes() const { return offset_; }

 private:
  struct ChunkIndex {
    uint64_t start_time = 0, end_time = 0, chunk_offset = 0, chunk_length = 0;
    std::map<uint16_t, uint64_t> message_index_offsets;
    uint64_t message_index_length = 0;
    uint64_t compressed_size = 0, uncompressed_size = 0;
  };
  void Emit(const std::string& bytes);
  void WriteChunk();
  void RequireOpen() const;

  std::string path_;
  McapWriterOptions options_;
  std::FILE* file_ = nullptr;
  uint64_t offset_ = 0;
  uint32_t crc_ = 0;  ///< running CRC32 of what was written: the data section, then the summary
  bool closed_ = false;
  std::vector<McapSchema> schemas_;
  std::vector<McapChannel> channels_;
  struct MetadataIndex {
    uint64_t offset = 0, length = 0;
    std::string name;
  };
  std::vector<MetadataIndex> metadata_indexes_;
  // The chunk being filled.
  std::string chunk_records_;
  uint64_t chunk_start_time_ = 0, chunk_end_time_ = 0;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_message_index_;  ///< log time, offset
  std::vector<ChunkIndex> chunk_indexes_;
  std::map<uint16_t, uint64_t> channel_message_counts_;
  uint64_t message_count_ = 0, chunk_count_ = 0;
  uint64_t first_time_ = UINT64_MAX, last_time_ = 0;
};

/// What ReadMcap found.
struct McapReadResult {
  std::string profile, library;
  std::map<uint16_t, McapSchema> schemas;
  std::map<uint16_t, McapChannel> channels;
  std::vector<McapMetadata> metadata;
  uint64_t messages = 0;
  uint64_t chunks = 0;
  bool data_end = false;  ///< the data section ended properly (DataEnd record, CRC checked)
  bool complete = false;  ///< data end, summary and footer all read
  /// Empty if the whole file read; else where and why reading stopped (the records before it
  /// were delivered).
  std::string problem;
};

/// Reads `path` from its start, calling `on_message` for every message in file order (after its
/// channel). Throws std::runtime_error only if the file cannot be opened or is not MCAP (no
/// magic); any later damage is reported in `problem`.
McapReadResult ReadMcap(const std::string& path,
                        const std::function<void(const McapChannel&, const McapMessage&)>& on_message);

/// True if `path` can be read and starts with the MCAP magic.
bool IsMcapFile(const std::string& path);

/// ReadMcap with the messages delivered in log-time order (file order for equal times): a
/// recorder writes in the order it drains its readers, which may differ from the log times by a
/// drain period; messages up to `window_ns` out of order in the file are put back in order.
/// Memory: the messages within the window.
McapReadResult ReadMcapInLogTimeOrder(const std::string& path, uint64_t window_ns,
                                      const std::function<void(const McapChannel&, const McapMessage&)>& on_message);

/// The summary section by the footer: schemas, channels, statistics and chunk count.
struct McapSummary {
  std::map<uint16_t, McapSchema> schemas;
  std::map<uint16_t, McapChannel> channels;
  uint64_t message_count = 0;
  uint32_t chunk_count = 0;
  uint64_t message_start_time = 0, message_end_time = 0;
  std::map<uint16_t, uint64_t> channel_message_counts;
  uint32_t chunk_indexes = 0;  ///< ChunkIndex records found
};
/// nullopt if the file has no (readable, CRC-valid) summary, e.g. a recording cut short.
std::optional<McapSummary> ReadMcapSummary(const std::string& path);

}  // namespace dpc::record
