#pragma once
// Reads a TraceWriter CSV (dpc/sim/trace_writer.h) and reduces every column to what a line
// plot of a given pixel width can show: the M4 envelope (Jugel et al., "M4: a visualization-
// oriented time series data aggregation", PVLDB 7(10), 2014).
//
// The time range [t_min, t_max] is split into B equal buckets, one per pixel column of the plot
// area; sample (t, y) falls in bucket ⌊(t − t_min)/(t_max − t_min) · B⌋ (clamped to B − 1).
// Of each bucket's samples, per column, only four are kept: the first, the last, the minimum
// and the maximum. A polyline through the kept points rasterizes like the one
// through all points at that width, so outliers (the extremes the paper discusses for the
// control signals, section IV) survive while a trace of any length becomes ≤ 4·B points per
// column.
//
// The file is streamed twice (pass 1: the time range; pass 2: the buckets); memory is
// O(columns · B), independent of the number of rows. Rows whose t_s is not finite are counted
// but not kept; non-finite values (nan, inf) of a column are skipped for that column.

#include <cstdint>
#include <string>
#include <vector>

namespace dpc {

/// The structure of a trace file, from its header line.
struct TraceHeader {
  /// Every column name, t_s first (kTraceFixedHeader's columns, then the control names).
  std::vector<std::string> columns;
  /// The control-signal columns: columns[kTraceFixedColumnCount …].
  std::vector<std::string> control_names;
  /// The comment lines before the header, without the leading "# ".
  std::vector<std::string> comment_lines;
  /// 1-based line number of the header line.
  int64_t header_line = 0;
};

/// One kept sample of a column.
struct EnvelopePoint {
  double t_s;
  double value;
};

/// The M4 envelope of every column of a trace except t_s.
struct TraceEnvelope {
  TraceHeader header;
  /// Data rows in the file.
  int64_t rows = 0;
  /// The finite time range; NaN when no row has a finite t_s.
  double t_min_s;
  double t_max_s;
  /// points[c - 1]: the kept samples of header.columns[c] (c ≥ 1), bucket by bucket (time
  /// order), in file order within a bucket: file order for a trace written in time order.
  std::vector<std::vector<EnvelopePoint>> points;
  /// min_value[c - 1], max_value[c - 1]: the extremes of the finite values of column c (exact:
  /// the envelope keeps them); NaN when the column has no finite value.
  std::vector<double> min_value;
  std::vector<double> max_value;

  /// The index into points / min_value / max_value of the column named `name`, or −1.
  int ColumnIndex(const std::string& name) const;
};

/// The most buckets ReadTraceEnvelope accepts.
inline constexpr int kMaxEnvelopeBuckets = 1 << 20;

/// Reads the comment lines and the header of a TraceWriter CSV.
/// @throws std::runtime_error naming the file if it cannot be opened, or if its first
///         non-comment line does not start with kTraceFixedHeader.
TraceHeader ReadTraceHeader(const std::string& trace_csv);

/// Reads the whole trace and reduces it to its M4 envelope over `bucket_count` buckets.
/// @throws std::invalid_argument unless 1 ≤ bucket_count ≤ kMaxEnvelopeBuckets;
///         std::runtime_error (file and line number) for an unreadable file, a bad header, a
///         row with the wrong number of fields or a field that is not a number.
TraceEnvelope ReadTraceEnvelope(const std::string& trace_csv, int bucket_count);

}  // namespace dpc
