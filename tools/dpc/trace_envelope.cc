#include "trace_envelope.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string_view>

#include "dpc/sim/trace_writer.h"

namespace dpc {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Reads a trace line by line, counting lines and dropping a trailing '\r'.
class TraceLineReader {
 public:
  explicit TraceLineReader(const std::string& path) : path_(path), in_(path) {
    if (!in_) {
      const int error = errno;
      throw std::runtime_error(
          fmt::format("cannot open trace '{}': {}", path, std::strerror(error)));
    }
  }

  bool Next(std::string* line) {
    if (!std::getline(in_, *line)) {
      if (in_.bad()) {
        throw std::runtime_error(fmt::format("reading trace '{}' failed after line {}", path_,
                                             line_number_));
      }
      return false;
    }
    ++line_number_;
    if (!line->empty() && line->back() == '\r') line->pop_back();
    return true;
  }

  // Reads the comment lines and the header; leaves the reader on the first data line.
  TraceHeader ReadHeader() {
    TraceHeader header;
    std::string line;
    while (Next(&line)) {
      if (line.empty()) continue;
      if (line[0] == '#') {
        const size_t text = line.size() > 1 && line[1] == ' ' ? 2 : 1;
        header.comment_lines.push_back(line.substr(text));
        continue;
      }
      const std::string_view fixed = kTraceFixedHeader;
      if (line.compare(0, fixed.size(), fixed) != 0 ||
          (line.size() > fixed.size() && line[fixed.size()] != ',')) {
        throw std::runtime_error(fmt::format(
            "{}:{}: not a trace header (expected it to start with \"{}\"): \"{}\"", path_,
            line_number_, fixed, line));
      }
      size_t begin = 0;
      while (true) {
        const size_t comma = line.find(',', begin);
        header.columns.push_back(line.substr(begin, comma - begin));
        if (comma == std::string::npos) break;
        begin = comma + 1;
      }
      header.control_names.assign(header.columns.begin() + kTraceFixedColumnCount,
                                  header.columns.end());
      header.header_line = line_number_;
      return header;
    }
    throw std::runtime_error(fmt::format("{}: no header line (empty or comments only)", path_));
  }

  const std::string& path() const { return path_; }
  int64_t line_number() const { return line_number_; }

 private:
  std::string path_;
  std::ifstream in_;
  int64_t line_number_ = 0;
};

// Parses `text` as a whole double ("inf", "nan" included).
bool ParseDouble(std::string_view text, double* value) {
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, *value);
  return ec == std::errc() && ptr == end;
}

// Splits `line` into exactly values->size() numbers; throws naming the file and line otherwise.
void ParseRow(const TraceLineReader& reader, const std::string& line,
              std::vector<double>* values) {
  size_t begin = 0;
  for (size_t column = 0; column < values->size(); ++column) {
    const size_t comma = line.find(',', begin);
    const bool last = column + 1 == values->size();
    if ((comma == std::string::npos) != last) {
      throw std::runtime_error(fmt::format("{}:{}: expected {} fields: \"{}\"", reader.path(),
                                           reader.line_number(), values->size(), line));
    }
    const std::string_view field(line.data() + begin,
                                 (last ? line.size() : comma) - begin);
    if (!ParseDouble(field, &(*values)[column])) {
      throw std::runtime_error(fmt::format("{}:{}: field {} \"{}\" is not a number",
                                           reader.path(), reader.line_number(), column + 1,
                                           field));
    }
    begin = comma + 1;
  }
}

// The M4 aggregate of one column in one bucket.
struct Bucket {
  struct Sample {
    int64_t row = -1;
    double t_s = 0.0;
    double value = 0.0;
  };
  Sample first, last, min, max;

  void Add(const Sample& sample) {
    if (first.row < 0) {
      first = last = min = max = sample;
      return;
    }
    last = sample;
    if (sample.value < min.value) min = sample;
    if (sample.value > max.value) max = sample;
  }

  // Appends the distinct kept samples in file order.
  void AppendTo(std::vector<EnvelopePoint>* points) const {
    if (first.row < 0) return;
    std::array<Sample, 4> kept = {first, min, max, last};
    std::sort(kept.begin(), kept.end(),
              [](const Sample& a, const Sample& b) { return a.row < b.row; });
    for (size_t i = 0; i < kept.size(); ++i) {
      if (i > 0 && kept[i].row == kept[i - 1].row) continue;
      points->push_back({kept[i].t_s, kept[i].value});
    }
  }
};

}  // namespace

int TraceEnvelope::ColumnIndex(const std::string& name) const {
  for (size_t c = 1; c < header.columns.size(); ++c) {
    if (header.columns[c] == name) return static_cast<int>(c) - 1;
  }
  return -1;
}

TraceHeader ReadTraceHeader(const std::string& trace_csv) {
  TraceLineReader reader(trace_csv);
  return reader.ReadHeader();
}

TraceEnvelope ReadTraceEnvelope(const std::string& trace_csv, int bucket_count) {
  if (bucket_count < 1 || bucket_count > kMaxEnvelopeBuckets) {
    throw std::invalid_argument(fmt::format(
        "ReadTraceEnvelope: bucket_count = {} must be in [1, {}]", bucket_count,
        kMaxEnvelopeBuckets));
  }
  TraceEnvelope envelope;
  std::string line;

  // Pass 1: the finite time range (only the first field of each row is parsed).
  double t_min_s = std::numeric_limits<double>::infinity();
  double t_max_s = -std::numeric_limits<double>::infinity();
  {
    TraceLineReader reader(trace_csv);
    envelope.header = reader.ReadHeader();
    while (reader.Next(&line)) {
      if (line.empty() || line[0] == '#') continue;
      double t_s = kNaN;
      const size_t comma = line.find(',');
      if (ParseDouble(std::string_view(line).substr(0, comma), &t_s) && std::isfinite(t_s)) {
        t_min_s = std::min(t_min_s, t_s);
        t_max_s = std::max(t_max_s, t_s);
      }
    }
  }
  const bool any_time = t_min_s <= t_max_s;
  envelope.t_min_s = any_time ? t_min_s : kNaN;
  envelope.t_max_s = any_time ? t_max_s : kNaN;

  // Pass 2: every field, into the buckets of every column.
  const size_t columns = envelope.header.columns.size();
  const size_t value_columns = columns - 1;
  std::vector<Bucket> buckets(value_columns * static_cast<size_t>(bucket_count));
  envelope.min_value.assign(value_columns, kNaN);
  envelope.max_value.assign(value_columns, kNaN);
  const double buckets_per_s =
      any_time && t_max_s > t_min_s ? bucket_count / (t_max_s - t_min_s) : 0.0;
  std::vector<double> values(columns);
  TraceLineReader reader(trace_csv);
  reader.ReadHeader();
  while (reader.Next(&line)) {
    if (line.empty() || line[0] == '#') continue;
    ParseRow(reader, line, &values);
    const int64_t row = envelope.rows++;
    const double t_s = values[0];
    if (!std::isfinite(t_s)) continue;
    const int bucket = std::clamp(static_cast<int>((t_s - t_min_s) * buckets_per_s), 0,
                                  bucket_count - 1);
    for (size_t c = 0; c < value_columns; ++c) {
      const double value = values[c + 1];
      if (!std::isfinite(value)) continue;
      buckets[c * static_cast<size_t>(bucket_count) + static_cast<size_t>(bucket)].Add(
          {row, t_s, value});
      // fmin/fmax ignore the NaN the extremes start as.
      envelope.min_value[c] = std::fmin(envelope.min_value[c], value);
      envelope.max_value[c] = std::fmax(envelope.max_value[c], value);
    }
  }

  envelope.points.resize(value_columns);
  for (size_t c = 0; c < value_columns; ++c) {
    for (int b = 0; b < bucket_count; ++b) {
      buckets[c * static_cast<size_t>(bucket_count) + static_cast<size_t>(b)].AppendTo(
          &envelope.points[c]);
    }
  }
  return envelope;
}

}  // namespace dpc
