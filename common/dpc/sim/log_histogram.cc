#include "dpc/sim/log_histogram.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace dpc {
namespace {

constexpr int kMantissaBits = 52;

uint64_t MagnitudeBits(double value) { return std::bit_cast<uint64_t>(value) & ~LogHistogram::kSignBit; }

}  // namespace

LogHistogram::LogHistogram(double min_magnitude, double max_magnitude, int sub_bucket_bits)
    : min_magnitude_(min_magnitude),
      max_magnitude_(max_magnitude),
      sub_bucket_bits_(sub_bucket_bits),
      min_(std::numeric_limits<double>::infinity()),
      max_(-std::numeric_limits<double>::infinity()) {
  if (!(std::isfinite(min_magnitude) && min_magnitude >= std::numeric_limits<double>::min())) {
    throw std::invalid_argument(fmt::format(
        "LogHistogram: min_magnitude = {:g} must be finite and at least the smallest normal "
        "double {:g}",
        min_magnitude, std::numeric_limits<double>::min()));
  }
  if (!(std::isfinite(max_magnitude) && max_magnitude > min_magnitude)) {
    throw std::invalid_argument(
        fmt::format("LogHistogram: max_magnitude = {:g} must be finite and greater than "
                    "min_magnitude = {:g}",
                    max_magnitude, min_magnitude));
  }
  if (sub_bucket_bits < 1 || sub_bucket_bits > kMaxSubBucketBits) {
    throw std::invalid_argument(
        fmt::format("LogHistogram: sub_bucket_bits = {} must be in [1, {}]", sub_bucket_bits,
                    kMaxSubBucketBits));
  }
  mantissa_shift_ = kMantissaBits - sub_bucket_bits;
  min_magnitude_bits_ = MagnitudeBits(min_magnitude);
  min_key_ = min_magnitude_bits_ >> mantissa_shift_;
  max_key_ = MagnitudeBits(max_magnitude) >> mantissa_shift_;
  const uint64_t bins_per_sign = max_key_ - min_key_ + 1;
  if (bins_per_sign > static_cast<uint64_t>((kMaxBinCount - 1) / 2)) {
    throw std::invalid_argument(fmt::format(
        "LogHistogram: [{:g}, {:g}] with sub_bucket_bits = {} needs {} bins; at most {} "
        "allowed (narrow the range or use fewer sub-bucket bits)",
        min_magnitude, max_magnitude, sub_bucket_bits, 2 * bins_per_sign + 1, kMaxBinCount));
  }
  zero_index_ = static_cast<int64_t>(bins_per_sign);
  bins_.assign(2 * bins_per_sign + 1, 0);
}

double LogHistogram::Percentile(double percent) const {
  if (!(percent >= 0.0 && percent <= 100.0)) {
    throw std::invalid_argument(
        fmt::format("LogHistogram::Percentile: percent = {} must be in [0, 100]", percent));
  }
  if (count_ == 0) return std::numeric_limits<double>::quiet_NaN();
  if (percent == 0.0) return min_;
  if (percent == 100.0) return max_;

  const double n = static_cast<double>(count_);
  const uint64_t rank = static_cast<uint64_t>(
      std::clamp(std::ceil(percent * n / 100.0), 1.0, n));  // 1-based nearest rank
  if (rank == 1) return min_;
  if (rank == count_) return max_;
  uint64_t below = 0;  // samples in the bins before `index`
  size_t index = 0;
  for (; index + 1 < bins_.size(); ++index) {
    if (below + bins_[index] >= rank) break;
    below += bins_[index];
  }
  if (static_cast<int64_t>(index) == zero_index_) return std::clamp(0.0, min_, max_);

  double lo = 0.0;
  double hi = 0.0;
  BinEdges(static_cast<int64_t>(index), &lo, &hi);
  lo = std::max(lo, min_);  // no sample lies outside [min, max]
  hi = std::min(hi, max_);
  const double in_bin = static_cast<double>(bins_[index]);
  const double position = (static_cast<double>(rank - below) - 0.5) / in_bin;  // in (0, 1)
  return std::clamp(lo + position * (hi - lo), min_, max_);
}

void LogHistogram::BinEdges(int64_t index, double* lo, double* hi) const {
  if (index == zero_index_) {
    *lo = -min_magnitude_;
    *hi = min_magnitude_;
    return;
  }
  const bool negative = index < zero_index_;
  const uint64_t key =
      min_key_ + static_cast<uint64_t>(negative ? zero_index_ - index - 1 : index - zero_index_ - 1);
  double magnitude_lo = std::bit_cast<double>(key << mantissa_shift_);
  double magnitude_hi = std::bit_cast<double>((key + 1) << mantissa_shift_);
  if (key == min_key_) magnitude_lo = std::max(magnitude_lo, min_magnitude_);
  if (key == max_key_) magnitude_hi = std::numeric_limits<double>::infinity();
  *lo = negative ? -magnitude_hi : magnitude_lo;
  *hi = negative ? -magnitude_lo : magnitude_hi;
}

void LogHistogram::Merge(const LogHistogram& other) {
  if (other.min_magnitude_ != min_magnitude_ || other.max_magnitude_ != max_magnitude_ ||
      other.sub_bucket_bits_ != sub_bucket_bits_) {
    throw std::invalid_argument(fmt::format(
        "LogHistogram::Merge: geometry (min_magnitude {:g}, max_magnitude {:g}, "
        "sub_bucket_bits {}) differs from this histogram's ({:g}, {:g}, {})",
        other.min_magnitude_, other.max_magnitude_, other.sub_bucket_bits_, min_magnitude_,
        max_magnitude_, sub_bucket_bits_));
  }
  // Read what `other` contributes before writing: `other` may be *this.
  const double other_sum = other.sum_;
  const double other_compensation = other.compensation_;
  for (size_t i = 0; i < bins_.size(); ++i) bins_[i] += other.bins_[i];
  count_ += other.count_;
  nan_count_ += other.nan_count_;
  min_ = std::min(min_, other.min_);
  max_ = std::max(max_, other.max_);
  AddToSum(other_sum);
  compensation_ += other_compensation;
}

void LogHistogram::Clear() noexcept {
  std::fill(bins_.begin(), bins_.end(), 0);
  count_ = 0;
  nan_count_ = 0;
  min_ = std::numeric_limits<double>::infinity();
  max_ = -std::numeric_limits<double>::infinity();
  sum_ = 0.0;
  compensation_ = 0.0;
}

double LogHistogram::min() const {
  return count_ == 0 ? std::numeric_limits<double>::quiet_NaN() : min_;
}

double LogHistogram::max() const {
  return count_ == 0 ? std::numeric_limits<double>::quiet_NaN() : max_;
}

double LogHistogram::sum() const {
  // Once the running sum is ±∞ or NaN the compensation is meaningless (∞ − ∞).
  return std::isfinite(sum_) ? sum_ + compensation_ : sum_;
}

double LogHistogram::mean() const {
  return count_ == 0 ? std::numeric_limits<double>::quiet_NaN()
                     : sum() / static_cast<double>(count_);
}

double LogHistogram::relative_bin_width() const { return std::ldexp(1.0, -sub_bucket_bits_); }

}  // namespace dpc
