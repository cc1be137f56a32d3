#pragma once
// Σ ln(x_i) over a stream of positive values without a logarithm per value.
//
// ln Π x_i = Σ ln x_i, and the product can be kept exactly enough as a mantissa and an integer
// exponent: each factor is one multiplication (relative rounding ≤ ε), and every few factors the
// mantissa's IEEE-754 exponent is moved into the integer (bit operations, no rounding), so the
// product neither underflows nor overflows. At the end Σ ln x_i = ln(mantissa) + exponent·ln 2.
// Over n values the absolute error of the sum is ≲ n·ε (1e9 values: ~1e-7 on a sum of ~1e10,
// i.e. ~1e-16 on the mean): better than adding n rounded logarithms. Four interleaved products
// let the loop vectorize.
//
// Values must be finite and in [kMinValue, kMaxValue]; the caller clamps (the simulator's leak
// fractions are floored at 1e-20 and are at most 1).

#include <bit>
#include <cmath>
#include <cstdint>

namespace dpc {

class LogSumAccumulator {
 public:
  static constexpr double kMinValue = 1e-30;
  static constexpr double kMaxValue = 1e30;

  /// Hot path: adds ln(values[i]) for i < count. No allocation.
  void AddBatch(const double* values, int count) noexcept {
    int i = 0;
    while (i + 4 <= count) {
      // At most kFactorsPerLane factors per lane between renormalizations: a mantissa in [1, 2)
      // times 8 factors in [1e-30, 1e30] stays within [1e-240, 2e240].
      const int rounds = std::min(kFactorsPerLane, (count - i) / 4);
      for (int r = 0; r < rounds; ++r, i += 4) {
        for (int lane = 0; lane < 4; ++lane) mantissa_[lane] *= values[i + lane];
      }
      Renormalize();
    }
    for (; i < count; ++i) {
      mantissa_[0] *= values[i];
      Renormalize();
    }
    count_ += count;
  }

  /// Σ ln x_i of everything added (0 when nothing was).
  double LogSum() const {
    double sum = static_cast<double>(exponent_) * 0.69314718055994530942;
    for (double m : mantissa_) sum += std::log(m);
    return sum;
  }
  int64_t count() const { return count_; }

 private:
  static constexpr int kFactorsPerLane = 8;

  void Renormalize() noexcept {
    for (int lane = 0; lane < 4; ++lane) {
      const uint64_t bits = std::bit_cast<uint64_t>(mantissa_[lane]);
      exponent_ += static_cast<int64_t>((bits >> 52) & 0x7FF) - 1023;
      mantissa_[lane] = std::bit_cast<double>((bits & kMantissaBits) | kExponentOfOne);
    }
  }

  static constexpr uint64_t kMantissaBits = (uint64_t{1} << 52) - 1;
  static constexpr uint64_t kExponentOfOne = uint64_t{1023} << 52;  // 1.0's exponent field

  double mantissa_[4] = {1.0, 1.0, 1.0, 1.0};  ///< each in [1, 2) after Renormalize
  int64_t exponent_ = 0;
  int64_t count_ = 0;
};

}  // namespace dpc
