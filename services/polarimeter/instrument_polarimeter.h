#pragma once
// A real polarimeter queried over a line protocol (PolarimeterDeviceConfig: SCPI-like text on a
// serial port or TCP), one query per bench sample, or read in stream mode (the instrument sends
// its readings by itself; each line is a sample when it arrives, the newest when several wait).
// Its reply holds S_out, S_in or both; the sample's time is when the reply arrived. A reply that does not come within
// response_timeout_s, or is not what was asked for (garbage, a cut line, |S| too small), gives
// no sample, is counted, and says why; a closed connection is reopened after reconnect_min_s,
// doubling up to reconnect_max_s, and no query waits longer than the timeout: the bench's
// loop is never held by the instrument.

#include <cstdint>
#include <optional>
#include <string>

#include "dpc/config/scenario_config.h"
#include "dpc/instrument/line_link.h"
#include "dpc/optics/stokes.h"

namespace dpc::services {

struct PolarimeterReading {
  std::optional<StokesVector> s_in;   ///< unit, when the instrument measures it
  std::optional<StokesVector> s_out;
  std::optional<double> power_w;      ///< finite, ≥ 0, when the instrument reports it
  int64_t reply_ns = 0;               ///< monotonic: when the reply arrived
};

class InstrumentPolarimeter {
 public:
  struct Counters {
    uint64_t queries = 0, readings = 0;
    uint64_t overtaken = 0;         ///< stream mode: lines skipped for a newer one
    uint64_t timeouts = 0;          ///< no reply in time
    uint64_t refused_replies = 0;   ///< a reply that was not a reading
    uint64_t connects = 0, failed_connects = 0;
  };

  /// `device` validated (ValidatePolarimeterDevice). Connects on the first Measure.
  explicit InstrumentPolarimeter(PolarimeterDeviceConfig device);

  /// One reading now (stream mode: the next line, waiting up to the response timeout), or
  /// nullopt with `*why` (no connection yet: a reconnection attempt when due, else at once; a
  /// timeout; a refused reply). `now_ns` monotonic.
  std::optional<PolarimeterReading> Measure(int64_t now_ns, std::string* why);

  const Counters& counters() const { return counters_; }
  /// Query → reply, µs, of the latest queries answered.
  const instrument::ExchangeTimes& query_times() const { return query_times_; }
  std::string name() const;
  const PolarimeterDeviceConfig& device() const { return device_; }

 private:
  PolarimeterDeviceConfig device_;
  instrument::LineLink link_;
  Counters counters_;
  instrument::ExchangeTimes query_times_;
  int64_t next_connect_ns_ = 0;
  double backoff_s_;
};

}  // namespace dpc::services
