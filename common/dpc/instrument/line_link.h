#pragma once
// The connection to a line-protocol instrument (SCPI-like text lines ending in "\n"): TCP to an
// IPv4 address (no name lookup) or a serial port (termios raw 8N1 at the configured baud; a
// pseudo-terminal's slave works too). Every call has a deadline: nothing here blocks longer
// than the timeout it is given, whatever the instrument does (a device that stops answering,
// answers garbage, or sends an endless line cannot stall its caller).

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dpc/config/scenario_config.h"

namespace dpc::instrument {

class LineLink {
 public:
  /// A reply line longer than this is refused as garbage (the rest of it is dropped).
  static constexpr size_t kMaxLineBytes = 256;

  /// `config` validated (ValidateWaveplateDevice / ValidatePolarimeterDevice). Opens nothing.
  /// Lines longer than `max_line_bytes` are refused.
  explicit LineLink(InstrumentLinkConfig config, size_t max_line_bytes = kMaxLineBytes);
  ~LineLink();
  LineLink(const LineLink&) = delete;
  LineLink& operator=(const LineLink&) = delete;

  /// Opens the connection within `timeout_s`; "" on success, else why not (refused, no such
  /// device, timed out). Closes an open one first.
  std::string Open(double timeout_s);
  void Close();
  bool is_open() const { return fd_ >= 0; }

  /// Writes `line` and "\n" within `timeout_s`; "" on success, else why not (the link is then
  /// closed).
  std::string WriteLine(const std::string& line, double timeout_s);
  /// The next line (without "\r\n" or "\n") within `timeout_s`; nullopt with `*why` on a timeout,
  /// a closed connection (the link is then closed), or a line over the limit.
  std::optional<std::string> ReadLine(double timeout_s, std::string* why);
  /// ReadLine, then whatever has already arrived after it without waiting (at most 32 KiB):
  /// the newest complete line, the older ones counted in `*overtaken` (a stream read slower
  /// than the instrument sends it never serves stale lines).
  std::optional<std::string> ReadNewestLine(double timeout_s, std::string* why, uint64_t* overtaken);
  /// Drops what arrived unasked (e.g. the late reply to a query that timed out), so that the
  /// next line read answers the next line written.
  void Discard();
  /// Discard, WriteLine, ReadLine: the reply to `line`, within `timeout_s` in all.
  std::optional<std::string> Query(const std::string& line, double timeout_s, std::string* why);

  /// "tcp 127.0.0.1:5025", "serial /dev/ttyUSB0 at 115200 Bd".
  std::string Describe() const;

 private:
  std::string OpenTcp(double timeout_s);
  std::string OpenSerial();
  /// ReadLine by `deadline`; a timeout is said as "no reply within `timeout_s`".
  std::optional<std::string> ReadLineBy(std::chrono::steady_clock::time_point deadline, double timeout_s,
                                        std::string* why);
  /// Reads what is available within `timeout_s` into buffer_; false on EOF or error (closed).
  bool Fill(double timeout_s, std::string* why);

  InstrumentLinkConfig config_;
  size_t max_line_bytes_;
  int fd_ = -1;
  std::string buffer_;  ///< received, not yet returned
  bool discarding_line_ = false;  ///< dropping the rest of an over-long line
};

/// The durations of the latest exchanges with an instrument (a query and its reply, a set and
/// its acknowledgement), for their percentiles: a fixed window of the last kCapacity, so it never
/// grows. Not thread-safe.
class ExchangeTimes {
 public:
  static constexpr size_t kCapacity = 4096;
  void Add(double us);
  size_t count() const { return count_; }
  /// The q-quantile (0…1) of the window, nearest rank; NaN when empty.
  double Percentile(double q) const;

 private:
  std::vector<double> window_;
  size_t next_ = 0, count_ = 0;
};

/// The Stokes vectors in a reply "s1,s2,s3[,s1,s2,s3]" (commas, optional spaces): exactly
/// `vectors` triples of finite numbers, each with |S| (the degree of polarization) in
/// [min_dop, 1.05]; written normalized into `out` (which must hold `vectors` entries). "" or
/// why not.
std::string ParseStokesReply(const std::string& reply, int vectors, double min_dop, StokesVector* out);

/// A finite number alone on the line (e.g. a voltage read back), or why not.
std::string ParseNumberReply(const std::string& reply, double* out);

/// The DAC's quantization over [volts_min, volts_max] with `bits` (0: none): the code of
/// `volts` (clamped into the full scale) and the voltage of that code.
struct DacPoint {
  int64_t code = 0;
  double volts = 0.0;
};
DacPoint Quantize(double volts, double volts_min, double volts_max, int bits);

}  // namespace dpc::instrument
