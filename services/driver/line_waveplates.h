#pragma once
// An electronic polarization controller (LiNbO₃, fibre squeezers, liquid crystal, piezo) driven
// over a line protocol (SCPI-like text on a serial port or TCP, WaveplateDeviceConfig): each
// control φ_i is the voltage of one channel, quantized to the device's DAC.
//
// The driver never waits for the device. Apply() hands the newest motion to an I/O thread and
// returns at once; the thread writes one set line per channel whose DAC code changed (all
// lines first, then their acknowledgements: one round trip per command) and always sends the
// newest motion (commands that arrive faster than the device answers, or within its settling_s
// of the last set, are coalesced). The device
// cannot ramp: a motion is applied as its point (Applied() has no rate).
//
// Faults: a refused connection, a reply later than response_timeout_s, a closed connection, a
// reply that is not the acknowledgement (garbage, an error message) → fault() says why, the link
// is closed and reopened after reconnect_min_s, doubling to reconnect_max_s; every refused
// reply is counted. While in fault, Apply() refuses (the driver holds the last good φ and says
// why). On reconnecting, the device (which may have lost power and forgotten its voltages) is
// first set to that held φ and acknowledged; only then is the fault cleared and the driver
// obeys controllers again. At start, with a read_command, the channels are read back and the
// waveplates are taken where they are (no jump after a driver restart).

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "dpc/config/scenario_config.h"
#include "dpc/instrument/line_link.h"
#include "waveplate_backend.h"

namespace dpc::services {

class LineWaveplates final : public WaveplateBackend {
 public:
  struct Counters {
    uint64_t sets = 0;              ///< set lines written
    uint64_t refused_replies = 0;   ///< replies that were not the acknowledgement
    uint64_t timeouts = 0;
    uint64_t connects = 0;          ///< connections made (the first one included)
    uint64_t failed_connects = 0;
  };
  using Log = std::function<void(bool warning, const std::string& text)>;

  /// `device` validated against the scenario's stages (ValidateWaveplateDevice); `controls` its
  /// control count; `initial_phi` (inside the ranges) is where the waveplates start unless the
  /// device can be read back within `connect_timeout_s` at start (then they start where they
  /// are, clamped into `ranges`). `log` gets what the operator should read (connections, faults);
  /// called from the I/O thread.
  LineWaveplates(WaveplateDeviceConfig device, const ControlVector& initial_phi,
                 const std::vector<ControlRange>& ranges, Log log, double connect_timeout_s = 1.0);
  ~LineWaveplates() override;
  LineWaveplates(const LineWaveplates&) = delete;
  LineWaveplates& operator=(const LineWaveplates&) = delete;

  DeviceLimits limits() const override;
  std::string Apply(const WaveplateMotion& motion) override;
  const WaveplateMotion& Applied() const override { return applied_; }
  std::string name() const override { return name_; }
  bool ramps() const override { return false; }
  std::string fault() const override;

  Counters counters() const;
  /// A command handed over → every changed channel acknowledged, µs: p50 and p99 of the latest.
  std::pair<double, double> ApplyTimesUs() const;
  /// Whether the φ the driver started from was read back from the device.
  bool started_from_read_back() const { return started_from_read_back_; }

 private:
  /// The channel number and the DAC point of control i at `volts`.
  instrument::DacPoint Dac(double volts) const;
  /// Writes every channel whose code differs from the device's (all of them if `all`), then
  /// reads the acknowledgements. "" or why not.
  std::string Send(const std::vector<instrument::DacPoint>& target, bool all);
  /// Opens the link, identifies the device. "" or why not.
  std::string Connect(double timeout_s);
  /// The channels read back, or why not.
  std::string ReadBack(std::vector<double>* volts);
  void Run();
  void SetFault(std::string why);
  void CountMissingReply();

  const WaveplateDeviceConfig device_;
  const std::string name_;
  const Log log_;
  std::vector<int> channels_;
  instrument::LineLink link_;  ///< the I/O thread's, after construction
  WaveplateMotion applied_;    ///< the driver's thread: what Apply accepted (a point)
  bool started_from_read_back_ = false;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<instrument::DacPoint> wanted_;  ///< the newest point to reach (guarded)
  uint64_t wanted_version_ = 0;               ///< counts Apply()s (guarded)
  std::string fault_;                          ///< guarded
  Counters counters_;                          ///< guarded
  instrument::ExchangeTimes apply_times_;      ///< guarded
  bool stop_ = false;                          ///< guarded

  std::vector<instrument::DacPoint> device_codes_;  ///< the I/O thread's: what the device acknowledged
  std::thread thread_;
};

}  // namespace dpc::services
