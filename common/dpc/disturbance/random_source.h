#pragma once
// The one source of randomness of the simulated optics: a seeded, reproducible generator of
// normal and uniform variates and uniform directions.
//
// Engine: MT19937-64 (Mt19937_64 below: boost::random::mt19937_64's outputs). Normal variates:
// boost::random::normal_distribution (a ziggurat). The engine seed is derived from (seed,
// stream) with SplitMix64 (Steele, Lea, Flood, OOPSLA 2014), so that the streams of one seed
// are independent and a run is reproducible from the scenario seed alone:
//
//   Mix64(z)  = SplitMix64's output function: z ← (z ⊕ z≫30)·0xbf58476d1ce4e5b9,
//               z ← (z ⊕ z≫27)·0x94d049bb133111eb, z ⊕ z≫31
//   γ         = 0x9e3779b97f4a7c15
//   h         = Mix64(seed + γ)                   (SplitMix64(seed)'s first output)
//   engine    = Mix64(h + γ·(stream + 1))         (SplitMix64(h)'s output number `stream`)
//
// For a fixed seed distinct streams give distinct engine seeds, and for a fixed stream distinct
// seeds do (Mix64 is a bijection). Streams in use: 0 free, 1 the input SOP
// (InputSopGenerator), 2 the polarimeter noise (PolarimeterNoise).
//
// Same (seed, stream) → the same sequence on every run. Not thread-safe: one owner per source.

#include <boost/random/normal_distribution.hpp>
#include <cmath>
#include <cstdint>

#include "dpc/optics/stokes.h"

namespace dpc {

/// MT19937-64 (Nishimura 2000), the generator of boost::random::mt19937_64 and
/// std::mt19937_64, with the same outputs for the same seed (a test compares them), written out
/// so that a block of outputs can be had at once: Fill twists and tempers whole runs of the
/// state, which vectorizes, where the library's engines go one output at a time.
class Mt19937_64 {
 public:
  using result_type = uint64_t;
  static constexpr int kStateSize = 312;
  explicit Mt19937_64(uint64_t seed);
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return ~result_type{0}; }
  /// Real-time. The next output.
  result_type operator()() {
    if (index_ == kStateSize) Twist();
    return Temper(state_[index_++]);
  }
  /// Real-time. out[0 … count) = the next `count` outputs (count ≥ 0).
  void Fill(uint64_t* out, int count);

 private:
  static uint64_t Temper(uint64_t y) {
    y ^= (y >> 29) & 0x5555555555555555ULL;
    y ^= (y << 17) & 0x71D67FFFEDA60000ULL;
    y ^= (y << 37) & 0xFFF7EEE000000000ULL;
    return y ^ (y >> 43);
  }
  void Twist();

  uint64_t state_[kStateSize];
  int index_ = kStateSize;
};

/// SplitMix64's output function Mix64 (see the file comment). A bijection of uint64_t.
uint64_t SplitMix64Mix(uint64_t z);

/// The mt19937_64 seed for (seed, stream): Mix64(Mix64(seed + γ) + γ·(stream + 1)).
uint64_t DeriveEngineSeed(uint64_t seed, uint64_t stream);

class RandomSource {
 public:
  /// A source seeded with DeriveEngineSeed(seed, stream). Never throws.
  explicit RandomSource(uint64_t seed, uint64_t stream = 0);

  /// Real-time. A standard normal variate N(0, 1).
  double Normal() { return normal_(engine_); }

  /// Real-time. out[0 … count) = `count` successive Normal() draws, bit for bit and leaving the
  /// engine where those calls would, faster: the engine's outputs are drawn a chunk at a time
  /// and the ziggurat's first try (boost's table, taken by ~99 % of draws, one engine output
  /// each) is evaluated for every output without a branch; a draw whose first try fails runs
  /// boost's own rejection from that output on. count ≥ 0.
  void NormalBlock(double* out, int count);

  /// Real-time. A uniform variate in [0, 1): the top 53 bits of one engine output · 2⁻⁵³.
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

  /// Real-time. A direction uniformly distributed on the unit sphere: three normal variates,
  /// normalized (a draw of norm < 1e-150, never seen in practice, is redrawn).
  Vector3 UnitVector() {
    for (;;) {
      const Vector3 v(Normal(), Normal(), Normal());
      const double norm_squared = v.squaredNorm();
      if (norm_squared > 1e-300) return v / std::sqrt(norm_squared);
    }
  }

  uint64_t seed() const { return seed_; }
  uint64_t stream() const { return stream_; }

 private:
  uint64_t seed_;
  uint64_t stream_;
  Mt19937_64 engine_;
  boost::random::normal_distribution<double> normal_;
};

}  // namespace dpc
