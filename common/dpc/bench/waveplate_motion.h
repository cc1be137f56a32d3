#pragma once
// The waveplates' motion: φ at a start time plus a rate, for a bounded interval of bench time,
//
//   φ(t) = phi + rate_per_s · (min(max(t, start_ns), end_ns) − start_ns).
//
// A driver applies a command as such a motion (a rate command ramps, a point command holds),
// a device backend executes it, the driver's state describes it, and the simulated bench
// evaluates it at each sample's time. A point is a motion with a zero rate.

#include <algorithm>
#include <cstdint>

#include "dpc/optics/stokes.h"

namespace dpc {

struct WaveplateMotion {
  ControlVector phi;          ///< at start_ns
  ControlVector rate_per_s;   ///< per second of bench time; zero: φ holds
  int64_t start_ns = 0;
  int64_t end_ns = 0;         ///< ≥ start_ns; end_ns − start_ns fits an int64
  bool moving = false;        ///< a non-zero rate over a non-empty interval

  /// A motion that holds `phi`.
  static WaveplateMotion Still(const ControlVector& phi) {
    WaveplateMotion motion;
    motion.phi = phi;
    motion.rate_per_s = ControlVector::Zero(phi.size());
    return motion;
  }

  /// Real-time. φ at bench time t_ns into `out` (no allocation once `out` has the size).
  void At(int64_t t_ns, ControlVector* out) const {
    *out = phi;
    if (moving) {
      const int64_t t = std::min(std::max(t_ns, start_ns), end_ns);
      *out += rate_per_s * (static_cast<double>(t - start_ns) * 1e-9);
    }
  }

  /// The motion from the point where this one ends, holding still.
  WaveplateMotion Stopped() const {
    WaveplateMotion still = *this;
    At(end_ns, &still.phi);
    still.rate_per_s.setZero();
    still.start_ns = end_ns;
    still.moving = false;
    return still;
  }
};

}  // namespace dpc
