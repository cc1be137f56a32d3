#pragma once
// Streams a closed-loop trace to a CSV file without keeping it in memory.
//
// File format (the plotting tools read it back, see tools/dpc/paper_figure.h):
//
//   # <comment line 1>                       one per comment line, each as "# " + line
//   # ...
//   t_s,s_in_1,s_in_2,s_in_3,s_out_1,s_out_2,s_out_3,error_deg,<control name 1>,...
//   <t_s>,<S_in>,<S_out>,<error_deg>,<φ_1>,...   one row per Write()
//
// t_s is printed with 12 significant digits ("{:.12g}": relative round-trip error ≤ 5e-12),
// every other value with 9 ("{:.9g}": ≤ 5e-9 relative); ±∞ and NaN print as inf and nan.
// Rows end in "\n" only.
//
// Rows are formatted into a buffer of kBufferBytes reserved once in the constructor and
// written with one fwrite() whenever less than kRowReserveBytes remain free, so Write() does
// not allocate: it is fit for the simulation loop (it does do file I/O every ~1 MiB).
// Not thread-safe.

#include <fmt/format.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "dpc/optics/stokes.h"

namespace dpc {

/// The columns of every trace before the control signals, as written in the header line.
inline constexpr std::string_view kTraceFixedHeader =
    "t_s,s_in_1,s_in_2,s_in_3,s_out_1,s_out_2,s_out_3,error_deg";
/// The number of columns in kTraceFixedHeader; the control signals follow.
inline constexpr int kTraceFixedColumnCount = 8;

class TraceWriter {
 public:
  /// Bytes reserved for the row buffer.
  static constexpr size_t kBufferBytes = size_t{1} << 20;
  /// Free space kept for the next row: far more than the longest row (8 + kMaxControls numbers
  /// of at most 24 characters each).
  static constexpr size_t kRowReserveBytes = 4096;

  /// Opens (truncates) `path` and writes the comment lines and the header into the buffer.
  /// @param control_names  one CSV column name per control signal, at most kMaxControls; each
  ///        non-empty, unique, without commas, quotes, whitespace or control characters.
  /// @param comment_lines  free text written as "# <line>"; no line breaks inside a line.
  /// @throws std::invalid_argument for a bad control name or comment line (before the file is
  ///         created); std::runtime_error naming `path` and strerror(errno) if the file cannot
  ///         be opened for writing.
  TraceWriter(const std::string& path, std::vector<std::string> control_names,
              std::vector<std::string> comment_lines);

  /// Flushes and closes the file; never throws (a failure is lost: call Flush() first to see it).
  ~TraceWriter();

  TraceWriter(const TraceWriter&) = delete;
  TraceWriter& operator=(const TraceWriter&) = delete;

  /// Appends one row. Hot path: no allocation.
  /// @throws std::invalid_argument if phi.size() differs from the number of control names;
  ///         std::runtime_error if writing a full buffer to the file fails.
  void Write(double t_s, const StokesVector& s_in, const StokesVector& s_out, double error_deg,
             const ControlVector& phi);

  /// Writes the buffer to the file and flushes the C stream.
  /// @throws std::runtime_error naming the path and strerror(errno) on a write error (e.g.
  ///         ENOSPC, disk full).
  void Flush();

  /// The number of rows written by Write() (header and comments not included).
  int64_t rows() const { return rows_; }
  const std::string& path() const { return path_; }
  const std::vector<std::string>& control_names() const { return control_names_; }

 private:
  // Writes the buffer to file_ and empties it; throws std::runtime_error on failure.
  void DrainBuffer();

  std::string path_;
  std::vector<std::string> control_names_;
  std::FILE* file_ = nullptr;
  fmt::memory_buffer buffer_;
  int64_t rows_ = 0;
};

}  // namespace dpc
