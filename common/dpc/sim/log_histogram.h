#pragma once
// A fixed-size histogram with logarithmic bins for signed values: streaming percentiles over
// runs of up to ~1e12 samples in O(1) memory (e.g. the pointing error of a long closed-loop run).
//
// Bins. A finite double |v| = 2^e · (1 + f), f ∈ [0, 1), is binned by its IEEE-754 bits, as
// HdrHistogram does: the bin key is the biased exponent followed by the top b = sub_bucket_bits
// bits of the mantissa,
//
//   key(|v|) = bits(|v|) >> (52 − b),
//
// so every binary octave [2^e, 2^(e+1)) is split into 2^b bins of equal width 2^(e−b), and the
// width of a bin relative to any value inside it is at most
//
//   w_rel = 2^−b                     (0.39 % for the default b = 8).
//
// No log() is evaluated: a key is one shift. Because IEEE-754 orders non-negative doubles like
// their bit patterns, keys are monotone in |v|. The bins, in increasing value order, are
//
//   [negative bins, most negative first] [zero bin] [positive bins, smallest first]
//
// with K = key(max_magnitude) − key(min_magnitude) + 1 bins per sign, 2K + 1 in all:
//   * |v| < min_magnitude (including ±0)        → the zero bin;
//   * min_magnitude ≤ |v|                      → the bin of key(|v|), the lowest one starting at
//                                                min_magnitude itself;
//   * |v| beyond the bin of max_magnitude (±∞) → the outermost bin of its sign (still counted);
//   * NaN                                       → no bin; counted in nan_count() only.
// min(), max(), count() and sum() are exact (sum() compensated, see below), independent of bins.
//
// Percentile (rank-based; "nearest rank, interpolated inside the bin"). With n = count() and
// the samples sorted as x_(1) ≤ … ≤ x_(n):
//   1. percent = 0 → min(), percent = 100 → max(); otherwise
//   2. the nearest rank k = ⌈percent · n / 100⌉, clamped to [1, n]; the exact nearest-rank
//      percentile, which the histogram estimates, is x_(k). k = 1 → min(), k = n → max();
//   3. otherwise, the bin holding rank k: the first bin whose cumulative count reaches k; say it
//      holds c samples, ranks k0 + 1 … k0 + c, and spans [lo, hi) intersected with
//      [min(), max()] (the far edge of an outermost bin is ±∞ before the intersection);
//   4. the c samples are taken as evenly spread over [lo, hi), the j-th (j = k − k0) at the
//      centre of the j-th of c equal sub-intervals:  estimate = lo + (j − ½)/c · (hi − lo).
//      The zero bin returns 0 (clamped to [min(), max()]) instead.
// Accuracy. The estimate and x_(k) both lie in [lo, hi), so for min_magnitude ≤ |x_(k)| ≤
// max_magnitude:
//   |estimate − x_(k)| < w_rel · |x_(k)|     always (one bin width, relative),
//   |estimate − x_(k)| ≤ w_rel · |x_(k)| / 2 when the bin holds a single sample (its centre),
// and typically well under half a bin when the bins around x_(k) hold several samples of a
// smooth distribution (the interpolation then tracks it; the tests measure ≤ 0.35 bin widths on
// 1e5 uniform, log-normal and normal samples). The tests check all three statements. In the zero bin the error is below
// min_magnitude (absolute). A percentile among samples beyond ±max_magnitude is only known to
// lie between the outermost bin's near edge and max() (min()); their count is exact.
//
// Sum. sum() uses compensated summation (Knuth's TwoSum per addition): its error is about
// ε·|Σx| + n·ε²·Σ|x| (ε = 2^−53) instead of n·ε·Σ|x| for naive summation, so the mean of 1e9
// samples is exact to ~1e-15 relative unless the samples cancel heavily. Once an infinite
// sample arrives the sum is ±∞ (NaN for +∞ and −∞ both).
//
// Memory: the bins are one std::vector<uint64_t> of 2K + 1 counters allocated once in the
// constructor (41 k bins, 328 KiB for the defaults); Add, Merge, Clear and Percentile never
// allocate. Counters are 64-bit: 1e12 samples in one bin are far from overflow.
// Not thread-safe: give each thread its own histogram and Merge them.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "dpc/optics/lanes.h"

namespace dpc {

class LogHistogram {
 public:
  /// The most bins (2K + 1) a histogram may have: 2^24 counters, 128 MiB.
  static constexpr int64_t kMaxBinCount = int64_t{1} << 24;
  /// The largest sub_bucket_bits accepted.
  static constexpr int kMaxSubBucketBits = 20;

  /// @param min_magnitude  smallest |v| that gets a logarithmic bin; smaller |v| go to the zero
  ///                       bin. Finite and ≥ the smallest normal double (2.2e-308).
  /// @param max_magnitude  largest |v| with a bin of its own; larger |v| go to the outermost
  ///                       bin. Finite and > min_magnitude.
  /// @param sub_bucket_bits  b in [1, kMaxSubBucketBits]: 2^b bins per octave, relative bin
  ///                       width 2^−b.
  /// @throws std::invalid_argument if an argument is out of range or the histogram would need
  ///         more than kMaxBinCount bins.
  explicit LogHistogram(double min_magnitude = 1e-12, double max_magnitude = 1e12,
                        int sub_bucket_bits = 8);

  /// Adds one sample. Real-time safe: O(1), no allocation, no log(), no exception.
  void Add(double value) noexcept;

  /// Hot path: adds values[0], values[stride], …, values[(count − 1)·stride]; the same as Add on
  /// each (the sum differs in the last bits: the batch is summed plainly, then compensated), with
  /// the running count, minimum and maximum kept in registers. Meant for batches of ~256.
  void AddBatch(const double* values, int count, std::ptrdiff_t stride = 1) noexcept;

  /// Hot path: four histograms of the same geometry at once. Adds column c of `values` (`count`
  /// rows of four, row-major) to histograms[c] for c < lanes ≤ 4 (columns beyond are ignored);
  /// the same as AddBatch on each column except for the last bits of sum(). A row's four bin
  /// indices, minima, maxima and sums are one vector operation each (e.g. the controls of one
  /// sample, four AddBatch calls' worth of arithmetic in one). Row i starts at
  /// values[i·row_stride] (row_stride ≥ 4: the four columns of a wider row).
  static void AddBatchLanes(LogHistogram* const* histograms, int lanes, const double* values,
                            int count, std::ptrdiff_t row_stride = 4) noexcept {
    AddBatchColumns<4>(histograms, lanes, values, count, row_stride);
  }
  /// The same for eight histograms (lanes ≤ 8, row_stride ≥ 8): one vector of eight doubles a
  /// row (e.g. one control of a batch's eight trajectories; one AVX-512 register where the build
  /// has it). Each column's bits equal AddBatchLanes's.
  static void AddBatchLanes8(LogHistogram* const* histograms, int lanes, const double* values,
                             int count, std::ptrdiff_t row_stride = 8) noexcept {
    AddBatchColumns<8>(histograms, lanes, values, count, row_stride);
  }

  /// The estimated percentile of the samples added so far (see the header comment for the
  /// exact definition and accuracy); NaN when there are none. O(number of bins); not for the
  /// real-time path. @throws std::invalid_argument unless 0 ≤ percent ≤ 100.
  double Percentile(double percent) const;

  /// Adds the samples of `other` to this histogram (`other` may be *this). Equivalent to having
  /// added all of them to one histogram, except for the rounding of sum(). No allocation.
  /// @throws std::invalid_argument unless `other` has the same min_magnitude, max_magnitude and
  ///         sub_bucket_bits.
  void Merge(const LogHistogram& other);

  /// Forgets every sample; keeps the geometry and the memory. No allocation.
  void Clear() noexcept;

  /// The number of non-NaN samples added.
  int64_t count() const { return static_cast<int64_t>(count_); }
  /// The number of NaN samples added (not in count(), not binned).
  int64_t nan_count() const { return static_cast<int64_t>(nan_count_); }
  /// The smallest / largest sample exactly; NaN when count() == 0.
  double min() const;
  double max() const;
  /// The compensated sum of the samples; 0 when count() == 0.
  double sum() const;
  /// sum() / count(); NaN when count() == 0.
  double mean() const;

  double min_magnitude() const { return min_magnitude_; }
  double max_magnitude() const { return max_magnitude_; }
  int sub_bucket_bits() const { return sub_bucket_bits_; }
  /// The width of a bin relative to any value inside it, at most: 2^−sub_bucket_bits.
  double relative_bin_width() const;

  static constexpr uint64_t kSignBit = uint64_t{1} << 63;
  static constexpr uint64_t kInfinityBits = 0x7FF0000000000000ULL;  ///< larger magnitudes: NaN
  /// The number of bins, 2K + 1 (including the zero bin).
  int64_t bin_count() const { return static_cast<int64_t>(bins_.size()); }

 private:
  // The value range [lo, hi) of bin `index` (for the zero bin: [-min_magnitude, min_magnitude));
  // the far edge of an outermost bin is ±∞ (it also holds everything beyond max_magnitude).
  void BinEdges(int64_t index, double* lo, double* hi) const;
  // Compensated addition of `value` into (sum_, compensation_) (TwoSum).
  void AddToSum(double value) noexcept;
  // Four values into four lanes' minimum, maximum and sum, NaNs left out (a comparison with a
  // NaN is false: it keeps the accumulator).
  template <typename V>
  [[gnu::always_inline]] static void AccumulateLanes(V value, V* low, V* high, V* sum) noexcept {
    *low = value < *low ? value : *low;
    *high = value > *high ? value : *high;
    *sum += value == value ? value : V{};
  }
  // The vectors of AddBatchColumns (GCC ignores a vector_size that depends on a template
  // parameter).
  template <int W>
  struct ColumnVectors;
  // AddBatchLanes (W = 4) and AddBatchLanes8 (W = 8): W columns, one vector of W doubles a row.
  template <int W>
  static void AddBatchColumns(LogHistogram* const* histograms, int lanes, const double* values,
                              int count, std::ptrdiff_t row_stride) noexcept;

  double min_magnitude_;
  double max_magnitude_;
  int sub_bucket_bits_;
  int mantissa_shift_;      // 52 − b
  uint64_t min_key_;        // key(min_magnitude)
  uint64_t max_key_;        // key(max_magnitude)
  uint64_t min_magnitude_bits_;
  int64_t zero_index_;      // K
  std::vector<uint64_t> bins_;

  uint64_t count_ = 0;
  uint64_t nan_count_ = 0;
  double min_;
  double max_;
  double sum_ = 0.0;
  double compensation_ = 0.0;
};

// Hot path: called once per sample; no allocation, no log(), one shift for the bin.
inline void LogHistogram::Add(double value) noexcept {
  const uint64_t bits = std::bit_cast<uint64_t>(value);
  const uint64_t magnitude_bits = bits & ~kSignBit;
  if (magnitude_bits > kInfinityBits) {  // NaN
    ++nan_count_;
    return;
  }
  ++count_;
  min_ = std::min(min_, value);
  max_ = std::max(max_, value);
  AddToSum(value);
  int64_t index = zero_index_;
  if (magnitude_bits >= min_magnitude_bits_) {
    const uint64_t key = std::min(magnitude_bits >> mantissa_shift_, max_key_);
    const int64_t offset = static_cast<int64_t>(key - min_key_) + 1;
    index = (bits & kSignBit) != 0 ? zero_index_ - offset : zero_index_ + offset;
  }
  ++bins_[static_cast<size_t>(index)];
}

inline void LogHistogram::AddToSum(double value) noexcept {
  // Knuth's TwoSum: the rounding error of sum_ + value, recovered exactly without a branch
  // (Neumaier's |sum| ≥ |value| test mispredicts for signals that swing around zero).
  const double total = sum_ + value;
  const double value_part = total - sum_;
  compensation_ += (sum_ - (total - value_part)) + (value - value_part);
  sum_ = total;
}

inline void LogHistogram::AddBatch(const double* values, int count,
                                   std::ptrdiff_t stride) noexcept {
  // Everything the loops read goes into locals first: the bin stores (uint64_t) could alias the
  // uint64_t members for the compiler, which would reload them on every value.
  uint64_t* const bins = bins_.data();
  const int shift = mantissa_shift_;
  // Magnitude bits are below 2^63: signed arithmetic is exact and vectorizes (AVX2 has no
  // unsigned 64-bit compare).
  const int64_t min_key = static_cast<int64_t>(min_key_), max_key = static_cast<int64_t>(max_key_);
  const int64_t min_bits = static_cast<int64_t>(min_magnitude_bits_);
  constexpr int64_t kInfinity = static_cast<int64_t>(kInfinityBits);
  const int64_t zero = zero_index_;
  const auto value_at = [values, stride](int i) { return values[i * stride]; };
  // Minimum, maximum and the sum, NaNs left out, four samples per vector operation
  // (AccumulateLanes): lane j takes the samples i ≡ j (mod 4), and
  // the lanes are folded in a fixed order, so the bits do not depend on the build. The sum is
  // blocked: plain in the four lanes (error ≲ count·ε of the batch sum), folded into the
  // compensated total once. The last count mod 4 samples one at a time.
  Lanes low = Splat(min_), high = Splat(max_), lane_sum = Splat(0.0);
  const int quad_end = count & ~3;
  for (int i = 0; i < quad_end; i += 4) {
    Lanes value;
    if (stride == 1) {
      std::memcpy(&value, values + i, sizeof value);
    } else {
      value = Lanes{value_at(i), value_at(i + 1), value_at(i + 2), value_at(i + 3)};
    }
    AccumulateLanes(value, &low, &high, &lane_sum);
  }
  // std::min/max keep the first operand against a NaN (the tail's samples).
  double minimum = std::min(std::min(low[0], low[1]), std::min(low[2], low[3]));
  double maximum = std::max(std::max(high[0], high[1]), std::max(high[2], high[3]));
  double sum = (lane_sum[0] + lane_sum[1]) + (lane_sum[2] + lane_sum[3]);
  for (int i = quad_end; i < count; ++i) {
    const double value = value_at(i);
    minimum = std::min(minimum, value);
    maximum = std::max(maximum, value);
    sum += std::isnan(value) ? 0.0 : value;
  }
  // The bins, a chunk at a time: first every index (branch-free, vectorized; a NaN is given the
  // zero bin and taken out again), then the increments. A slowly varying signal (an error near
  // lock, a control) puts consecutive values in the same bin, and increments of one counter
  // wait for each other through memory (~7 cycles each): the chunk's four quarters are counted
  // interleaved, so consecutive increments are to unrelated bins.
  constexpr int kChunk = 256;
  int64_t index[kChunk];
  uint64_t nans = 0;
  for (int start = 0; start < count; start += kChunk) {
    const int n = std::min(kChunk, count - start);
    int64_t chunk_nans = 0;
    for (int i = 0; i < n; ++i) {
      const int64_t bits = std::bit_cast<int64_t>(value_at(start + i));
      const int64_t magnitude = bits & INT64_MAX;
      const bool nan = magnitude > kInfinity;
      chunk_nans += nan;
      const int64_t key = std::min(magnitude >> shift, max_key);
      const int64_t offset = magnitude >= min_bits && !nan ? key - min_key + 1 : 0;
      index[i] = bits < 0 ? zero - offset : zero + offset;
    }
    const int quarter = n / 4;
    for (int j = 0; j < quarter; ++j) {
      ++bins[index[j]];
      ++bins[index[j + quarter]];
      ++bins[index[j + 2 * quarter]];
      ++bins[index[j + 3 * quarter]];
    }
    for (int j = 4 * quarter; j < n; ++j) ++bins[index[j]];
    bins[zero] -= static_cast<uint64_t>(chunk_nans);
    nans += static_cast<uint64_t>(chunk_nans);
  }
  count_ += static_cast<uint64_t>(count) - nans;
  nan_count_ += nans;
  min_ = minimum;
  max_ = maximum;
  AddToSum(sum);
}

template <>
struct LogHistogram::ColumnVectors<4> {
  using Values = double __attribute__((vector_size(32)));
  using Bits = int64_t __attribute__((vector_size(32)));
  using UnsignedBits = uint64_t __attribute__((vector_size(32)));
};
template <>
struct LogHistogram::ColumnVectors<8> {
  using Values = double __attribute__((vector_size(64)));
  using Bits = int64_t __attribute__((vector_size(64)));
  using UnsignedBits = uint64_t __attribute__((vector_size(64)));
};

template <int W>
inline void LogHistogram::AddBatchColumns(LogHistogram* const* histograms, int lanes,
                                          const double* values, int count,
                                          std::ptrdiff_t row_stride) noexcept {
  using Values = typename ColumnVectors<W>::Values;
  using Bits = typename ColumnVectors<W>::Bits;
  using UnsignedBits = typename ColumnVectors<W>::UnsignedBits;
  const auto splat = [](int64_t x) { return Bits{} + x; };
  const LogHistogram& geometry = *histograms[0];
  // As in AddBatch: magnitude bits are below 2^63, signed arithmetic is exact.
  const int shift = geometry.mantissa_shift_;
  const Bits min_key = splat(static_cast<int64_t>(geometry.min_key_));
  const Bits max_key = splat(static_cast<int64_t>(geometry.max_key_));
  const Bits min_bits = splat(static_cast<int64_t>(geometry.min_magnitude_bits_));
  const Bits infinity = splat(static_cast<int64_t>(kInfinityBits));
  const Bits zero = splat(geometry.zero_index_);
  uint64_t* bins[W] = {};
  Values low = Values{} + INFINITY, high = Values{} - INFINITY, sum{};
  for (int c = 0; c < lanes; ++c) {
    bins[c] = histograms[c]->bins_.data();
    low[c] = histograms[c]->min_;
    high[c] = histograms[c]->max_;
  }
  Bits nans = splat(0);
  constexpr int kChunk = 256;
  Bits index[kChunk];
  for (int start = 0; start < count; start += kChunk) {
    const int n = std::min(kChunk, count - start);
    Bits chunk_nans = splat(0);
    for (int i = 0; i < n; ++i) {
      Values value;
      std::memcpy(&value, values + row_stride * (start + i), sizeof value);
      AccumulateLanes(value, &low, &high, &sum);
      const Bits bits = std::bit_cast<Bits>(value);
      const Bits magnitude = bits & INT64_MAX;
      const Bits nan = magnitude > infinity;  // −1 (all bits) where true
      chunk_nans -= nan;
      const Bits unclamped = std::bit_cast<Bits>(std::bit_cast<UnsignedBits>(magnitude) >> shift);
      const Bits key = unclamped < max_key ? unclamped : max_key;
      const Bits offset = (magnitude >= min_bits) & ~nan & (key - min_key + 1);
      index[i] = bits < 0 ? zero - offset : zero + offset;
    }
    // Quarters interleaved, as in AddBatch: consecutive increments of a counter are far apart.
    const auto add_row = [&](int row) {
      for (int c = 0; c < lanes; ++c) ++bins[c][index[row][c]];
    };
    const int quarter = n / 4;
    for (int j = 0; j < quarter; ++j) {
      add_row(j);
      add_row(j + quarter);
      add_row(j + 2 * quarter);
      add_row(j + 3 * quarter);
    }
    for (int j = 4 * quarter; j < n; ++j) add_row(j);
    for (int c = 0; c < lanes; ++c) bins[c][geometry.zero_index_] -= static_cast<uint64_t>(chunk_nans[c]);
    nans += chunk_nans;
  }
  for (int c = 0; c < lanes; ++c) {
    LogHistogram& h = *histograms[c];
    h.count_ += static_cast<uint64_t>(count) - static_cast<uint64_t>(nans[c]);
    h.nan_count_ += static_cast<uint64_t>(nans[c]);
    h.min_ = low[c];
    h.max_ = high[c];
    h.AddToSum(sum[c]);
  }
}

}  // namespace dpc
