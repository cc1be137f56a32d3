#include "dpc/record/mcap.h"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <cerrno>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <queue>
#include <stdexcept>
#include <tuple>
#include <vector>

#include <fmt/format.h>

namespace dpc::record {
namespace {

constexpr char kMagic[] = "\x89MCAP0\r\n";
constexpr size_t kMagicSize = 8;

enum Opcode : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

uint32_t Crc32(uint32_t crc, const std::string& bytes) {
  return static_cast<uint32_t>(
      crc32(crc, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
}

// --- little-endian encoding -------------------------------------------------------------------

void PutU8(std::string* out, uint8_t v) { out->push_back(static_cast<char>(v)); }
template <typename T>
void PutLe(std::string* out, T v) {
  for (size_t i = 0; i < sizeof(T); ++i) out->push_back(static_cast<char>((static_cast<uint64_t>(v) >> (8 * i)) & 0xFF));
}
void PutString(std::string* out, const std::string& s) {
  PutLe<uint32_t>(out, static_cast<uint32_t>(s.size()));
  out->append(s);
}
void PutStringMap(std::string* out, const std::map<std::string, std::string>& map) {
  std::string entries;
  for (const auto& [key, value] : map) {
    PutString(&entries, key);
    PutString(&entries, value);
  }
  PutString(out, entries);  // uint32 byte length, then the entries
}
std::string Record(uint8_t opcode, const std::string& content) {
  std::string out;
  PutU8(&out, opcode);
  PutLe<uint64_t>(&out, content.size());
  out.append(content);
  return out;
}

std::string SchemaRecord(const McapSchema& s) {
  std::string c;
  PutLe<uint16_t>(&c, s.id);
  PutString(&c, s.name);
  PutString(&c, s.encoding);
  PutString(&c, s.data);
  return Record(kSchema, c);
}
std::string ChannelRecord(const McapChannel& ch) {
  std::string c;
  PutLe<uint16_t>(&c, ch.id);
  PutLe<uint16_t>(&c, ch.schema_id);
  PutString(&c, ch.topic);
  PutString(&c, ch.message_encoding);
  PutStringMap(&c, ch.metadata);
  return Record(kChannel, c);
}

std::string Compress(McapCompression compression, const std::string& data) {
  switch (compression) {
    case McapCompression::kNone:
      return data;
    case McapCompression::kZstd: {
      std::string out(ZSTD_compressBound(data.size()), '\0');
      const size_t n = ZSTD_compress(out.data(), out.size(), data.data(), data.size(), 3);
      if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
      out.resize(n);
      return out;
    }
    case McapCompression::kLz4: {
      LZ4F_preferences_t preferences{};
      preferences.frameInfo.contentSize = data.size();
      std::string out(LZ4F_compressFrameBound(data.size(), &preferences), '\0');
      const size_t n = LZ4F_compressFrame(out.data(), out.size(), data.data(), data.size(), &preferences);
      if (LZ4F_isError(n)) throw std::runtime_error(std::string("lz4: ") + LZ4F_getErrorName(n));
      out.resize(n);
      return out;
    }
  }
  return data;
}

// Decompresses a chunk's records into exactly `size` bytes; "" on success, else why not.
std::string Decompress(const std::string& compression, const std::string& data, uint64_t size, std::string* out) {
  // Writers make chunks of a few MiB (this one 1 MiB): a claim beyond 256 MiB is refused
  // before anything is allocated for it.
  if (size > (uint64_t{1} << 28)) return fmt::format("a chunk of {} bytes uncompressed (at most 256 MiB)", size);
  if (compression.empty()) {
    if (data.size() != size) return "an uncompressed chunk whose size is not its records'";
    *out = data;
    return {};
  }
  out->assign(size, '\0');
  if (compression == "zstd") {
    const size_t n = ZSTD_decompress(out->data(), out->size(), data.data(), data.size());
    if (ZSTD_isError(n)) return std::string("zstd: ") + ZSTD_getErrorName(n);
    if (n != size) return "zstd: the records are not the chunk's size";
    return {};
  }
  if (compression == "lz4") {
    LZ4F_dctx* context = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION))) return "lz4: no context";
    std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> guard(context, LZ4F_freeDecompressionContext);
    size_t written = 0, read = 0;
    while (read < data.size()) {
      size_t dst = out->size() - written, src = data.size() - read;
      const size_t hint = LZ4F_decompress(context, out->data() + written, &dst, data.data() + read, &src, nullptr);
      if (LZ4F_isError(hint)) return std::string("lz4: ") + LZ4F_getErrorName(hint);
      written += dst;
      read += src;
      if (hint == 0) break;
      if (dst == 0 && src == 0) return "lz4: no progress";
    }
    if (written != size) return "lz4: the records are not the chunk's size";
    return {};
  }
  return "unknown compression '" + compression.substr(0, 32) + "'";
}

// --- decoding -----------------------------------------------------------------------------------

// Reads fields from one record's content; any read past the end sets `bad`.
class Fields {
 public:
  explicit Fields(const std::string& bytes) : bytes_(bytes) {}
  template <typename T>
  T Le() {
    if (pos_ + sizeof(T) > bytes_.size()) return Fail<T>();
    uint64_t v = 0;
    for (size_t i = 0; i < sizeof(T); ++i) v |= uint64_t{static_cast<uint8_t>(bytes_[pos_ + i])} << (8 * i);
    pos_ += sizeof(T);
    return static_cast<T>(v);
  }
  std::string Bytes(uint64_t n) {
    if (n > bytes_.size() - pos_) return Fail<std::string>();
    std::string s = bytes_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  std::string String() { return Bytes(Le<uint32_t>()); }
  std::map<std::string, std::string> StringMap() {
    std::map<std::string, std::string> map;
    const std::string text = String();
    Fields entries(text);
    while (!bad_ && !entries.done()) {
      std::string key = entries.String();
      std::string value = entries.String();
      if (entries.bad()) bad_ = true;
      map.emplace(std::move(key), std::move(value));
    }
    return map;
  }
  std::map<uint16_t, uint64_t> U16U64Map() {
    std::map<uint16_t, uint64_t> map;
    const std::string text = String();
    Fields entries(text);
    while (!bad_ && !entries.done()) {
      const auto key = entries.Le<uint16_t>();
      const auto value = entries.Le<uint64_t>();
      if (entries.bad()) bad_ = true;
      map.emplace(key, value);
    }
    return map;
  }
  std::string Rest() { return Bytes(bytes_.size() - pos_); }
  bool bad() const { return bad_; }
  bool done() const { return pos_ >= bytes_.size(); }

 private:
  template <typename T>
  T Fail() {
    bad_ = true;
    pos_ = bytes_.size();
    return T{};
  }
  const std::string& bytes_;
  size_t pos_ = 0;
  bool bad_ = false;
};

// Records from a sequence of bytes (a chunk's records).
struct RawRecord {
  uint8_t opcode;
  std::string content;
};

class File {
 public:
  explicit File(const std::string& path) : file_(std::fopen(path.c_str(), "rb")) {
    if (file_ == nullptr) throw std::runtime_error(fmt::format("cannot open {}: {}", path, std::strerror(errno)));
  }
  ~File() { std::fclose(file_); }
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  bool Read(void* out, size_t n) { return std::fread(out, 1, n, file_) == n; }
  bool Seek(int64_t offset, int whence) { return std::fseek(file_, static_cast<long>(offset), whence) == 0; }
  int64_t Tell() { return std::ftell(file_); }

 private:
  std::FILE* file_;
};

// One record at the file's position: false at a clean end or on a truncated record (`problem`
// says which).
bool ReadRecord(File* file, RawRecord* record, std::string* problem, uint64_t max_length) {
  uint8_t head[9];
  const int64_t at = file->Tell();
  if (!file->Read(head, 1)) return false;  // end of file
  if (!file->Read(head + 1, 8)) {
    *problem = fmt::format("a record cut short at byte {}", at);
    return false;
  }
  uint64_t length = 0;
  for (int i = 0; i < 8; ++i) length |= uint64_t{head[1 + i]} << (8 * i);
  if (length > max_length) {
    *problem = fmt::format("a record at byte {} claims {} bytes (more than the file holds)", at, length);
    return false;
  }
  record->opcode = head[0];
  record->content.resize(length);
  if (length > 0 && !file->Read(record->content.data(), length)) {
    *problem = fmt::format("a record cut short at byte {} (opcode 0x{:02x}, {} bytes)", at, head[0], length);
    return false;
  }
  return true;
}

bool ParseSchema(const std::string& content, McapSchema* s) {
  Fields f(content);
  s->id = f.Le<uint16_t>();
  s->name = f.String();
  s->encoding = f.String();
  s->data = f.String();
  return !f.bad();
}
bool ParseChannel(const std::string& content, McapChannel* ch) {
  Fields f(content);
  ch->id = f.Le<uint16_t>();
  ch->schema_id = f.Le<uint16_t>();
  ch->topic = f.String();
  ch->message_encoding = f.String();
  ch->metadata = f.StringMap();
  return !f.bad();
}

}  // namespace

McapCompression ParseMcapCompression(const std::string& name) {
  if (name.empty() || name == "none") return McapCompression::kNone;
  if (name == "zstd") return McapCompression::kZstd;
  if (name == "lz4") return McapCompression::kLz4;
  throw std::invalid_argument("compression '" + name + "': give zstd, lz4 or none");
}

const char* McapCompressionName(McapCompression compression) {
  switch (compression) {
    case McapCompression::kZstd: return "zstd";
    case McapCompression::kLz4: return "lz4";
    case McapCompression::kNone: break;
  }
  return "";
}

// --- writer -------------------------------------------------------------------------------------

McapWriter::McapWriter(const std::string& path, McapWriterOptions options)
    : path_(path), options_(std::move(options)) {
  file_ = std::fopen(path.c_str(), "wb");
  if (file_ == nullptr) throw std::runtime_error(fmt::format("cannot create {}: {}", path, std::strerror(errno)));
  Emit(std::string(kMagic, kMagicSize));
  std::string header;
  PutString(&header, "");  // profile
  PutString(&header, options_.library);
  Emit(Record(kHeader, header));
}

McapWriter::~McapWriter() {
  try {
    Close();
  } catch (...) {  // a destructor does not throw; Close() says it to callers that ask
  }
  if (file_ != nullptr) std::fclose(file_);
}

void McapWriter::RequireOpen() const {
  if (closed_) throw std::runtime_error(path_ + " is closed");
}

void McapWriter::Emit(const std::string& bytes) {
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) {
    throw std::runtime_error(fmt::format("cannot write {}: {}", path_, std::strerror(errno)));
  }
  crc_ = Crc32(crc_, bytes);
  offset_ += bytes.size();
}

uint16_t McapWriter::AddSchema(const std::string& name, const std::string& encoding, const std::string& data) {
  RequireOpen();
  if (schemas_.size() >= std::numeric_limits<uint16_t>::max()) throw std::length_error("65535 schemas");
  McapSchema schema{static_cast<uint16_t>(schemas_.size() + 1), name, encoding, data};
  Emit(SchemaRecord(schema));
  schemas_.push_back(std::move(schema));
  return schemas_.back().id;
}

uint16_t McapWriter::AddChannel(uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                                const std::map<std::string, std::string>& metadata) {
  RequireOpen();
  if (schema_id > schemas_.size()) throw std::invalid_argument(fmt::format("no schema {}", schema_id));
  if (channels_.size() > std::numeric_limits<uint16_t>::max()) throw std::length_error("65536 channels");
  McapChannel channel{static_cast<uint16_t>(channels_.size()), schema_id, topic, message_encoding, metadata};
  Emit(ChannelRecord(channel));
  channels_.push_back(std::move(channel));
  return channels_.back().id;
}

void McapWriter::Write(const McapMessage& message) {
  RequireOpen();
  if (message.channel_id >= channels_.size()) {
    throw std::invalid_argument(fmt::format("no channel {}", message.channel_id));
  }
  std::string content;
  PutLe<uint16_t>(&content, message.channel_id);
  PutLe<uint32_t>(&content, message.sequence);
  PutLe<uint64_t>(&content, message.log_time_ns);
  PutLe<uint64_t>(&content, message.publish_time_ns);
  content.append(message.data);
  if (chunk_records_.empty()) {
    chunk_start_time_ = message.log_time_ns;
    chunk_end_time_ = message.log_time_ns;
  }
  chunk_start_time_ = std::min(chunk_start_time_, message.log_time_ns);
  chunk_end_time_ = std::max(chunk_end_time_, message.log_time_ns);
  chunk_message_index_[message.channel_id].emplace_back(message.log_time_ns, chunk_records_.size());
  chunk_records_ += Record(kMessage, content);
  ++message_count_;
  ++channel_message_counts_[message.channel_id];
  first_time_ = std::min(first_time_, message.log_time_ns);
  last_time_ = std::max(last_time_, message.log_time_ns);
  if (chunk_records_.size() >= options_.chunk_size_bytes) WriteChunk();
}

void McapWriter::WriteMetadata(const McapMetadata& metadata) {
  RequireOpen();
  std::string content;
  PutString(&content, metadata.name);
  PutStringMap(&content, metadata.values);
  const std::string record = Record(kMetadata, content);
  metadata_indexes_.push_back({offset_, record.size(), metadata.name});
  Emit(record);
}

void McapWriter::WriteChunk() {
  if (chunk_records_.empty()) return;
  const std::string compressed = Compress(options_.compression, chunk_records_);
  std::string content;
  PutLe<uint64_t>(&content, chunk_start_time_);
  PutLe<uint64_t>(&content, chunk_end_time_);
  PutLe<uint64_t>(&content, chunk_records_.size());
  PutLe<uint32_t>(&content, Crc32(0, chunk_records_));
  PutString(&content, McapCompressionName(options_.compression));
  PutLe<uint64_t>(&content, compressed.size());
  content.append(compressed);
  ChunkIndex index;
  index.start_time = chunk_start_time_;
  index.end_time = chunk_end_time_;
  index.chunk_offset = offset_;
  const std::string chunk = Record(kChunk, content);
  index.chunk_length = chunk.size();
  index.compressed_size = compressed.size();
  index.uncompressed_size = chunk_records_.size();
  Emit(chunk);
  const uint64_t indexes_start = offset_;
  for (const auto& [channel, entries] : chunk_message_index_) {
    std::string records;
    for (const auto& [time, at] : entries) {
      PutLe<uint64_t>(&records, time);
      PutLe<uint64_t>(&records, at);
    }
    std::string index_content;
    PutLe<uint16_t>(&index_content, channel);
    PutString(&index_content, records);  // uint32 byte length, then the entries
    index.message_index_offsets[channel] = offset_;
    Emit(Record(kMessageIndex, index_content));
  }
  index.message_index_length = offset_ - indexes_start;
  chunk_indexes_.push_back(std::move(index));
  ++chunk_count_;
  chunk_records_.clear();
  chunk_message_index_.clear();
}

void McapWriter::Flush() {
  RequireOpen();
  WriteChunk();
  if (std::fflush(file_) != 0) throw std::runtime_error(fmt::format("cannot write {}: {}", path_, std::strerror(errno)));
}

void McapWriter::Close() {
  if (closed_) return;
  closed_ = true;
  WriteChunk();
  std::string data_end;
  PutLe<uint32_t>(&data_end, crc_);
  Emit(Record(kDataEnd, data_end));

  // The summary: each group's records, then one SummaryOffset per group.
  const uint64_t summary_start = offset_;
  crc_ = 0;  // from here on: the summary's CRC
  std::vector<std::tuple<uint8_t, uint64_t, uint64_t>> groups;
  const auto group = [&](uint8_t opcode, const std::vector<std::string>& records) {
    if (records.empty()) return;
    const uint64_t start = offset_;
    for (const auto& r : records) Emit(r);
    groups.emplace_back(opcode, start, offset_ - start);
  };
  std::vector<std::string> records;
  for (const auto& s : schemas_) records.push_back(SchemaRecord(s));
  group(kSchema, records);
  records.clear();
  for (const auto& ch : channels_) records.push_back(ChannelRecord(ch));
  group(kChannel, records);
  std::string statistics;
  PutLe<uint64_t>(&statistics, message_count_);
  PutLe<uint16_t>(&statistics, static_cast<uint16_t>(schemas_.size()));
  PutLe<uint32_t>(&statistics, static_cast<uint32_t>(channels_.size()));
  PutLe<uint32_t>(&statistics, 0);  // attachments
  PutLe<uint32_t>(&statistics, static_cast<uint32_t>(metadata_indexes_.size()));
  PutLe<uint32_t>(&statistics, static_cast<uint32_t>(chunk_count_));
  PutLe<uint64_t>(&statistics, message_count_ ? first_time_ : 0);
  PutLe<uint64_t>(&statistics, message_count_ ? last_time_ : 0);
  std::string counts;
  for (const auto& [channel, count] : channel_message_counts_) {
    PutLe<uint16_t>(&counts, channel);
    PutLe<uint64_t>(&counts, count);
  }
  PutString(&statistics, counts);
  group(kStatistics, {Record(kStatistics, statistics)});
  records.clear();
  for (const MetadataIndex& index : metadata_indexes_) {
    std::string c;
    PutLe<uint64_t>(&c, index.offset);
    PutLe<uint64_t>(&c, index.length);
    PutString(&c, index.name);
    records.push_back(Record(kMetadataIndex, c));
  }
  group(kMetadataIndex, records);
  records.clear();
  for (const auto& index : chunk_indexes_) {
    std::string c;
    PutLe<uint64_t>(&c, index.start_time);
    PutLe<uint64_t>(&c, index.end_time);
    PutLe<uint64_t>(&c, index.chunk_offset);
    PutLe<uint64_t>(&c, index.chunk_length);
    std::string offsets;
    for (const auto& [channel, at] : index.message_index_offsets) {
      PutLe<uint16_t>(&offsets, channel);
      PutLe<uint64_t>(&offsets, at);
    }
    PutString(&c, offsets);
    PutLe<uint64_t>(&c, index.message_index_length);
    PutString(&c, McapCompressionName(options_.compression));
    PutLe<uint64_t>(&c, index.compressed_size);
    PutLe<uint64_t>(&c, index.uncompressed_size);
    records.push_back(Record(kChunkIndex, c));
  }
  group(kChunkIndex, records);
  const uint64_t summary_offset_start = offset_;
  for (const auto& [opcode, start, length] : groups) {
    std::string c;
    PutU8(&c, opcode);
    PutLe<uint64_t>(&c, start);
    PutLe<uint64_t>(&c, length);
    Emit(Record(kSummaryOffset, c));
  }
  // Footer: its CRC covers the summary through the footer's summary_offset_start.
  std::string footer_head;
  PutU8(&footer_head, kFooter);
  PutLe<uint64_t>(&footer_head, 8 + 8 + 4);
  PutLe<uint64_t>(&footer_head, summary_start);
  PutLe<uint64_t>(&footer_head, summary_offset_start);
  Emit(footer_head);
  std::string footer_tail;
  PutLe<uint32_t>(&footer_tail, crc_);
  footer_tail.append(kMagic, kMagicSize);
  Emit(footer_tail);
  if (std::fflush(file_) != 0) throw std::runtime_error(fmt::format("cannot write {}: {}", path_, std::strerror(errno)));
}

// --- reader -------------------------------------------------------------------------------------

McapReadResult ReadMcap(const std::string& path,
                        const std::function<void(const McapChannel&, const McapMessage&)>& on_message) {
  File file(path);
  char magic[kMagicSize];
  if (!file.Read(magic, kMagicSize) || std::memcmp(magic, kMagic, kMagicSize) != 0) {
    throw std::runtime_error(path + " is not an MCAP file (no magic)");
  }
  file.Seek(0, SEEK_END);
  const uint64_t file_size = static_cast<uint64_t>(file.Tell());
  file.Seek(kMagicSize, SEEK_SET);

  McapReadResult result;
  uint32_t crc = Crc32(0, std::string(kMagic, kMagicSize));
  // One record of the data section (or of a chunk); false: stop (problem set).
  std::function<bool(const RawRecord&)> take = [&](const RawRecord& r) -> bool {
    switch (r.opcode) {
      case kHeader: {
        Fields f(r.content);
        result.profile = f.String();
        result.library = f.String();
        if (f.bad()) result.problem = "a malformed header";
        return !f.bad();
      }
      case kSchema: {
        McapSchema s;
        if (!ParseSchema(r.content, &s)) return (result.problem = "a malformed schema record").empty();
        result.schemas[s.id] = std::move(s);
        return true;
      }
      case kChannel: {
        McapChannel ch;
        if (!ParseChannel(r.content, &ch)) return (result.problem = "a malformed channel record").empty();
        result.channels[ch.id] = std::move(ch);
        return true;
      }
      case kMessage: {
        Fields f(r.content);
        McapMessage m;
        m.channel_id = f.Le<uint16_t>();
        m.sequence = f.Le<uint32_t>();
        m.log_time_ns = f.Le<uint64_t>();
        m.publish_time_ns = f.Le<uint64_t>();
        m.data = f.Rest();
        if (f.bad()) return (result.problem = "a malformed message record").empty();
        const auto channel = result.channels.find(m.channel_id);
        if (channel == result.channels.end()) {
          result.problem = fmt::format("a message of channel {}, which no channel record defined", m.channel_id);
          return false;
        }
        ++result.messages;
        on_message(channel->second, m);
        return true;
      }
      case kChunk: {
        Fields f(r.content);
        f.Le<uint64_t>();  // start time
        f.Le<uint64_t>();  // end time
        const auto size = f.Le<uint64_t>();
        const auto records_crc = f.Le<uint32_t>();
        const std::string compression = f.String();
        const std::string compressed = f.Bytes(f.Le<uint64_t>());
        if (f.bad()) return (result.problem = "a malformed chunk record").empty();
        std::string records;
        if (std::string why = Decompress(compression, compressed, size, &records); !why.empty()) {
          result.problem = "a chunk that does not decompress: " + why;
          return false;
        }
        if (records_crc != 0 && Crc32(0, records) != records_crc) {
          result.problem = "a chunk whose records fail their CRC";
          return false;
        }
        ++result.chunks;
        Fields inner(records);
        while (!inner.done()) {
          RawRecord sub;
          sub.opcode = inner.Le<uint8_t>();
          sub.content = inner.Bytes(inner.Le<uint64_t>());
          if (inner.bad()) return (result.problem = "a chunk with a malformed record").empty();
          if (!take(sub)) return false;
        }
        return true;
      }
      case kMetadata: {
        Fields f(r.content);
        McapMetadata m;
        m.name = f.String();
        m.values = f.StringMap();
        if (f.bad()) return (result.problem = "a malformed metadata record").empty();
        result.metadata.push_back(std::move(m));
        return true;
      }
      default:  // indexes, attachments, records of later versions: not needed to read the data
        return true;
    }
  };
  RawRecord record;
  for (;;) {
    const int64_t at = file.Tell();
    std::string problem;
    if (!ReadRecord(&file, &record, &problem, file_size)) {
      result.problem = problem.empty() ? "the file ends before its data end record" : problem;
      break;
    }
    if (record.opcode == kDataEnd) {
      Fields f(record.content);
      const auto stored = f.Le<uint32_t>();
      if (stored != 0 && stored != crc) {
        result.problem = "the data section fails its CRC";
        break;
      }
      result.data_end = true;
      // The summary and the footer follow; ReadMcapSummary checks them.
      result.complete = ReadMcapSummary(path).has_value();
      if (!result.complete) result.problem = "no readable summary after the data end";
      break;
    }
    // The running CRC of the data section (the record as it is in the file).
    std::string raw;
    PutU8(&raw, record.opcode);
    PutLe<uint64_t>(&raw, record.content.size());
    crc = Crc32(Crc32(crc, raw), record.content);
    if (!take(record)) {
      result.problem += fmt::format(" (at byte {})", at);
      break;
    }
  }
  return result;
}

std::optional<McapSummary> ReadMcapSummary(const std::string& path) {
  File file(path);
  if (!file.Seek(0, SEEK_END)) return std::nullopt;
  const int64_t size = file.Tell();
  constexpr int64_t kFooterSize = 1 + 8 + 8 + 8 + 4 + kMagicSize;
  if (size < static_cast<int64_t>(kMagicSize) + kFooterSize) return std::nullopt;
  std::string footer(kFooterSize, '\0');
  if (!file.Seek(size - kFooterSize, SEEK_SET) || !file.Read(footer.data(), footer.size())) return std::nullopt;
  if (footer.compare(kFooterSize - kMagicSize, kMagicSize, std::string(kMagic, kMagicSize)) != 0 ||
      static_cast<uint8_t>(footer[0]) != kFooter) {
    return std::nullopt;
  }
  Fields f(footer);
  f.Le<uint8_t>();
  f.Le<uint64_t>();
  const auto summary_start = f.Le<uint64_t>();
  f.Le<uint64_t>();  // summary offset start
  const auto summary_crc = f.Le<uint32_t>();
  const int64_t footer_at = size - kFooterSize;
  if (summary_start == 0 || summary_start > static_cast<uint64_t>(footer_at)) return std::nullopt;
  std::string summary(static_cast<size_t>(footer_at - static_cast<int64_t>(summary_start)), '\0');
  if (!file.Seek(static_cast<int64_t>(summary_start), SEEK_SET) || !file.Read(summary.data(), summary.size())) {
    return std::nullopt;
  }
  if (summary_crc != 0 && Crc32(Crc32(0, summary), footer.substr(0, 1 + 8 + 8 + 8)) != summary_crc) {
    return std::nullopt;
  }
  McapSummary s;
  Fields records(summary);
  while (!records.done()) {
    const auto opcode = records.Le<uint8_t>();
    const std::string content = records.Bytes(records.Le<uint64_t>());
    if (records.bad()) return std::nullopt;
    if (opcode == kSchema) {
      McapSchema schema;
      if (!ParseSchema(content, &schema)) return std::nullopt;
      s.schemas[schema.id] = std::move(schema);
    } else if (opcode == kChannel) {
      McapChannel channel;
      if (!ParseChannel(content, &channel)) return std::nullopt;
      s.channels[channel.id] = std::move(channel);
    } else if (opcode == kStatistics) {
      Fields st(content);
      s.message_count = st.Le<uint64_t>();
      st.Le<uint16_t>();
      st.Le<uint32_t>();
      st.Le<uint32_t>();
      st.Le<uint32_t>();
      s.chunk_count = st.Le<uint32_t>();
      s.message_start_time = st.Le<uint64_t>();
      s.message_end_time = st.Le<uint64_t>();
      s.channel_message_counts = st.U16U64Map();
      if (st.bad()) return std::nullopt;
    } else if (opcode == kChunkIndex) {
      ++s.chunk_indexes;
    }
  }
  return s;
}

bool IsMcapFile(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return false;
  char magic[kMagicSize] = {};
  const bool is_mcap = std::fread(magic, 1, kMagicSize, file) == kMagicSize && std::memcmp(magic, kMagic, kMagicSize) == 0;
  std::fclose(file);
  return is_mcap;
}

McapReadResult ReadMcapInLogTimeOrder(const std::string& path, uint64_t window_ns,
                                      const std::function<void(const McapChannel&, const McapMessage&)>& on_message) {
  struct Held {
    uint64_t order = 0;
    McapMessage message;
  };
  const auto later = [](const Held& a, const Held& b) {
    return std::tie(a.message.log_time_ns, a.order) > std::tie(b.message.log_time_ns, b.order);
  };
  std::priority_queue<Held, std::vector<Held>, decltype(later)> held(later);
  std::map<uint16_t, McapChannel> channels;
  uint64_t order = 0;
  const auto release = [&] {
    on_message(channels.at(held.top().message.channel_id), held.top().message);
    held.pop();
  };
  McapReadResult result = ReadMcap(path, [&](const McapChannel& channel, const McapMessage& message) {
    channels.try_emplace(channel.id, channel);
    held.push({order++, message});
    while (!held.empty() && held.top().message.log_time_ns + window_ns < message.log_time_ns) release();
  });
  while (!held.empty()) release();
  return result;
}

}  // namespace dpc::record
