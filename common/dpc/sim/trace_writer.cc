#include "dpc/sim/trace_writer.h"

#include <fmt/compile.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace dpc {
namespace {

void RequireValidControlName(const std::string& name) {
  if (name.empty()) {
    throw std::invalid_argument("TraceWriter: a control name is empty");
  }
  for (const char c : name) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == ',' || c == '"' || c == '\'' || byte <= 0x20 || byte == 0x7F) {
      throw std::invalid_argument(fmt::format(
          "TraceWriter: control name '{}' contains a comma, quote, whitespace or control "
          "character (byte 0x{:02x}); CSV column names must not",
          name, byte));
    }
  }
}

void RequireValidCommentLine(const std::string& line) {
  if (line.find_first_of("\r\n") != std::string::npos) {
    throw std::invalid_argument(fmt::format(
        "TraceWriter: comment line '{}' contains a line break; pass one line per element",
        line));
  }
}

}  // namespace

TraceWriter::TraceWriter(const std::string& path, std::vector<std::string> control_names,
                         std::vector<std::string> comment_lines)
    : path_(path), control_names_(std::move(control_names)) {
  if (control_names_.size() > static_cast<size_t>(kMaxControls)) {
    throw std::invalid_argument(fmt::format("TraceWriter: {} control names; at most {}",
                                            control_names_.size(), kMaxControls));
  }
  for (size_t i = 0; i < control_names_.size(); ++i) {
    RequireValidControlName(control_names_[i]);
    for (size_t j = 0; j < i; ++j) {
      if (control_names_[j] == control_names_[i]) {
        throw std::invalid_argument(fmt::format(
            "TraceWriter: control name '{}' appears twice; CSV column names must be unique",
            control_names_[i]));
      }
    }
  }
  for (const std::string& line : comment_lines) RequireValidCommentLine(line);

  file_ = std::fopen(path_.c_str(), "wb");
  if (file_ == nullptr) {
    const int error = errno;
    throw std::runtime_error(fmt::format("TraceWriter: cannot open '{}' for writing: {}", path_,
                                         std::strerror(error)));
  }
  buffer_.reserve(kBufferBytes);
  auto out = fmt::appender(buffer_);
  for (const std::string& line : comment_lines) out = fmt::format_to(out, "# {}\n", line);
  out = fmt::format_to(out, "{}", kTraceFixedHeader);
  for (const std::string& name : control_names_) out = fmt::format_to(out, ",{}", name);
  buffer_.push_back('\n');
  // Long comments may have grown the buffer; keep kRowReserveBytes free for Write().
  if (buffer_.size() + kRowReserveBytes > buffer_.capacity()) DrainBuffer();
}

TraceWriter::~TraceWriter() {
  if (file_ == nullptr) return;
  if (buffer_.size() > 0) {
    // Best effort: a destructor must not throw. Flush() reports errors.
    [[maybe_unused]] const size_t written = std::fwrite(buffer_.data(), 1, buffer_.size(), file_);
  }
  std::fclose(file_);
}

// Hot path: formats into the reserved buffer (fmt compiled format strings), no allocation.
void TraceWriter::Write(double t_s, const StokesVector& s_in, const StokesVector& s_out,
                        double error_deg, const ControlVector& phi) {
  if (static_cast<size_t>(phi.size()) != control_names_.size()) {
    throw std::invalid_argument(fmt::format(
        "TraceWriter::Write: {} control values for {} control columns in '{}'", phi.size(),
        control_names_.size(), path_));
  }
  auto out = fmt::appender(buffer_);
  out = fmt::format_to(out, FMT_COMPILE("{:.12g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}"),
                       t_s, s_in.x(), s_in.y(), s_in.z(), s_out.x(), s_out.y(), s_out.z(),
                       error_deg);
  for (Eigen::Index i = 0; i < phi.size(); ++i) {
    out = fmt::format_to(out, FMT_COMPILE(",{:.9g}"), phi[i]);
  }
  buffer_.push_back('\n');
  ++rows_;
  if (buffer_.size() + kRowReserveBytes > buffer_.capacity()) DrainBuffer();
}

void TraceWriter::DrainBuffer() {
  if (buffer_.size() == 0) return;
  const size_t size = buffer_.size();
  const size_t written = std::fwrite(buffer_.data(), 1, size, file_);
  const int error = errno;
  buffer_.clear();  // keeps the capacity; on failure the rows are lost either way
  if (written != size) {
    throw std::runtime_error(fmt::format("TraceWriter: writing '{}' failed after {} of {} bytes: {}",
                                         path_, written, size, std::strerror(error)));
  }
}

void TraceWriter::Flush() {
  DrainBuffer();
  if (std::fflush(file_) != 0) {
    const int error = errno;
    throw std::runtime_error(
        fmt::format("TraceWriter: flushing '{}' failed: {}", path_, std::strerror(error)));
  }
}

}  // namespace dpc
