#include "dpc/disturbance/random_source.h"

#include <algorithm>
#include <bit>

namespace dpc {
namespace {

constexpr uint64_t kGoldenGamma = 0x9e3779b97f4a7c15ULL;

}  // namespace

uint64_t SplitMix64Mix(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

uint64_t DeriveEngineSeed(uint64_t seed, uint64_t stream) {
  const uint64_t h = SplitMix64Mix(seed + kGoldenGamma);
  return SplitMix64Mix(h + kGoldenGamma * (stream + 1));
}

Mt19937_64::Mt19937_64(uint64_t seed) {
  // The reference initialization (init_genrand64), as boost's seed(value) and std's.
  state_[0] = seed;
  for (int i = 1; i < kStateSize; ++i) {
    const uint64_t previous = state_[i - 1];
    state_[i] = 6364136223846793005ULL * (previous ^ (previous >> 62)) + static_cast<uint64_t>(i);
  }
}

void Mt19937_64::Twist() {
  // The reference recurrence, x_i ← x_(i+m) ⊕ A·(upper(x_i) | lower(x_(i+1))), in three runs
  // whose elements do not depend on each other within a run (m = 156 = n / 2): each vectorizes.
  constexpr int kShift = kStateSize / 2;  // m
  constexpr uint64_t kUpper = 0xFFFFFFFF80000000ULL, kLower = 0x7FFFFFFFULL;
  constexpr uint64_t kMatrix = 0xB5026F5AA96619E9ULL;
  const auto mix = [](uint64_t current, uint64_t next, uint64_t far) {
    const uint64_t x = (current & kUpper) | (next & kLower);
    return far ^ (x >> 1) ^ ((0 - (x & 1)) & kMatrix);  // a mask: AVX2 has no 64-bit multiply
  };
  for (int i = 0; i < kShift; ++i) state_[i] = mix(state_[i], state_[i + 1], state_[i + kShift]);
  for (int i = kShift; i < kStateSize - 1; ++i) {
    state_[i] = mix(state_[i], state_[i + 1], state_[i - kShift]);
  }
  state_[kStateSize - 1] = mix(state_[kStateSize - 1], state_[0], state_[kShift - 1]);
  index_ = 0;
}

void Mt19937_64::Fill(uint64_t* out, int count) {
  while (count > 0) {
    if (index_ == kStateSize) Twist();
    const int n = std::min(count, kStateSize - index_);
    const uint64_t* state = state_ + index_;
    for (int j = 0; j < n; ++j) out[j] = Temper(state[j]);
    index_ += n;
    out += n;
    count -= n;
  }
}

RandomSource::RandomSource(uint64_t seed, uint64_t stream)
    : seed_(seed), stream_(stream), engine_(DeriveEngineSeed(seed, stream)) {}

namespace {

// An engine that returns the outputs already drawn into a chunk, then the engine's next ones:
// boost's normal_distribution run on it consumes outputs in the order it would on the engine.
class ChunkEngine {
 public:
  using result_type = Mt19937_64::result_type;
  ChunkEngine(const uint64_t* outputs, int position, int count, Mt19937_64* engine)
      : outputs_(outputs), position_(position), count_(count), engine_(engine) {}
  static constexpr result_type min() { return Mt19937_64::min(); }
  static constexpr result_type max() { return Mt19937_64::max(); }
  result_type operator()() { return position_ < count_ ? outputs_[position_++] : (*engine_)(); }
  int position() const { return position_; }

 private:
  const uint64_t* outputs_;
  int position_;
  int count_;
  Mt19937_64* engine_;
};

// v < 2⁵² as a double, exactly, with integer and floating-point operations that vectorize:
// 2⁵² + v has v as its mantissa.
inline double ExactDouble(uint64_t v) {
  return std::bit_cast<double>(v | 0x4330000000000000ULL) - 0x1.0p52;
}

}  // namespace

void RandomSource::NormalBlock(double* out, int count) {
  const double* const table_x = boost::random::detail::normal_table<double>::table_x;
  const double sigma = normal_.sigma(), mean = normal_.mean();
  constexpr int kChunk = 128;
  uint64_t outputs[kChunk];
  double first_try[kChunk];
  int64_t rejected[kChunk];
  int rejects[kChunk + 1];
  int done = 0;
  while (done < count) {
    const int n = std::min(kChunk, count - done);
    engine_.Fill(outputs, n);
    // boost::random::detail::unit_normal_distribution's first try on one output u
    // (generate_int_float_pair<double, 8> with a 64-bit engine): the low 8 bits are the sign
    // (bit 0) and the table row; bit 11 is cleared and u >> 8 scaled by 2⁻⁵⁶ is the fraction.
    // Branch-free, so that it vectorizes: u >> 8 (56 bits) is converted as its high 24 and low
    // 32 bits, each exactly, and one rounded addition: the correctly rounded conversion (AVX2
    // has no vector conversion of 64-bit integers).
    for (int j = 0; j < n; ++j) {
      const uint64_t u = outputs[j];
      const uint64_t row = (u & 0xFF) >> 1;
      const uint64_t bits = (u & ~(uint64_t{1} << 11)) >> 8;
      const double high = ExactDouble(bits >> 32) * 0x1.0p32;
      const double low = ExactDouble(bits & 0xFFFFFFFFULL);
      const double fraction = (high + low) * 0x1.0p-56;
      const double x = fraction * table_x[row];
      rejected[j] = !(x < table_x[row + 1]);
      // x·(±1) as boost computes it; ±1 from the sign bit, +1 for an odd bucket (a select
      // compiles to a branch that mispredicts every other draw).
      const double sign = std::bit_cast<double>(0x3FF0000000000000ULL | (~u & 1) << 63);
      first_try[j] = x * sign * sigma + mean;
    }
    // The rejected outputs' positions (~1 %), without a branch per output.
    int reject_count = 0;
    for (int j = 0; j < n; ++j) {
      rejects[reject_count] = j;
      reject_count += static_cast<int>(rejected[j]);
    }
    rejects[reject_count] = n;
    // In draw order: the accepted first tries up to the next rejected output are the draws; a
    // rejected one runs boost's rejection from that output on (it redoes the first try, then
    // draws more outputs: from the chunk, then the engine), which may consume later outputs.
    // Outputs drawn into the chunk are all consumed: each draw takes at least one.
    int position = 0, made = 0;
    for (int r = 0; r <= reject_count && position < n; ++r) {
      const int stop = rejects[r];
      if (stop < position) continue;  // consumed by an earlier rejection
      for (; position < stop; ++position) out[done + made++] = first_try[position];
      if (stop == n) break;
      ChunkEngine chunk(outputs, position, n, &engine_);
      out[done + made++] = normal_(chunk);
      position = chunk.position();
    }
    for (; made < n; ++made) out[done + made] = normal_(engine_);
    done += n;
  }
}

}  // namespace dpc
