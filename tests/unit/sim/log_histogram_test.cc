#include "dpc/sim/log_histogram.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace dpc {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// The percents checked against the exact sorted percentiles.
std::vector<double> CheckedPercents() {
  std::vector<double> percents = {0.0, 0.001, 0.01, 0.1, 1.0, 99.0, 99.9, 99.99, 99.999, 100.0};
  for (double p = 2.5; p < 99.0; p += 2.5) percents.push_back(p);
  return percents;
}

// The exact nearest-rank percentile x_(k), k = ⌈p·n/100⌉ clamped to [1, n] (the definition the
// histogram estimates).
double ExactPercentile(const std::vector<double>& sorted, double percent) {
  const double n = static_cast<double>(sorted.size());
  const double rank = std::clamp(std::ceil(percent * n / 100.0), 1.0, n);
  return sorted[static_cast<size_t>(rank) - 1];
}

class LogHistogramTest : public ::testing::Test {
 protected:
  static constexpr int kSampleCount = 100'000;

  // Adds `samples` to histogram_ and checks every percent in CheckedPercents():
  //   |estimate − exact| < w_rel·|exact|   (one bin width, the documented bound), or, in the
  //   zero bin, < min_magnitude. Returns the largest error in units of w_rel·|exact|.
  double AddAndCheckPercentiles(std::vector<double> samples) {
    for (double x : samples) histogram_.Add(x);
    std::sort(samples.begin(), samples.end());
    const double w_rel = histogram_.relative_bin_width();
    double worst_in_bin_widths = 0.0;
    for (double percent : CheckedPercents()) {
      const double exact = ExactPercentile(samples, percent);
      const double estimate = histogram_.Percentile(percent);
      const double error = std::abs(estimate - exact);
      if (std::abs(exact) < histogram_.min_magnitude()) {
        EXPECT_LT(error, histogram_.min_magnitude()) << "percent " << percent;
        continue;
      }
      EXPECT_LT(error, w_rel * std::abs(exact))
          << "percent " << percent << ": estimate " << estimate << ", exact " << exact;
      worst_in_bin_widths = std::max(worst_in_bin_widths, error / (w_rel * std::abs(exact)));
    }
    return worst_in_bin_widths;
  }

  std::mt19937_64 rng_{20240917};
  LogHistogram histogram_;
};

TEST_F(LogHistogramTest, UniformPercentilesWithinHalfABin) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<double> samples(kSampleCount);
  for (double& x : samples) x = uniform(rng_);
  // A smooth distribution: the in-bin interpolation stays under half a bin width.
  EXPECT_LT(AddAndCheckPercentiles(samples), 0.5);
}

TEST_F(LogHistogramTest, LogNormalOverTenDecadesPercentiles) {
  // log10(x) ~ N(0, 5/3): ±3σ spans 10 decades, 1e-5 … 1e5.
  std::lognormal_distribution<double> log_normal(0.0, 5.0 / 3.0 * std::log(10.0));
  std::vector<double> samples(kSampleCount);
  for (double& x : samples) x = log_normal(rng_);
  EXPECT_LT(AddAndCheckPercentiles(samples), 0.5);
}

TEST_F(LogHistogramTest, SignedNormalPercentiles) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> samples(kSampleCount);
  for (double& x : samples) x = normal(rng_);
  EXPECT_LT(AddAndCheckPercentiles(samples), 0.5);
  EXPECT_LT(histogram_.Percentile(0.1), 0.0);
  EXPECT_GT(histogram_.Percentile(99.9), 0.0);
}

TEST_F(LogHistogramTest, SparseTailWithinOneBinWidth) {
  // 200 samples over 20 decades: mostly one sample per bin, some bins with two or three
  // bunched ones; the documented bound (one bin width) must hold everywhere.
  std::uniform_real_distribution<double> decades(-10.0, 10.0);
  std::vector<double> samples(200);
  for (double& x : samples) x = std::pow(10.0, decades(rng_));
  AddAndCheckPercentiles(samples);
}

TEST_F(LogHistogramTest, SingleSampleInABinIsWithinHalfABinWidth) {
  const double w_rel = histogram_.relative_bin_width();
  for (double x : {1.0, 1.001, 1.0039, 3.14159, 7.9999, 1e-7 * 1.3, 6.02e11}) {
    histogram_.Clear();
    histogram_.Add(0.5 * x);
    histogram_.Add(x);  // the median, alone in its bin
    histogram_.Add(2.0 * x);
    EXPECT_LE(std::abs(histogram_.Percentile(50.0) - x), 0.5 * w_rel * x) << x;
  }
}

TEST_F(LogHistogramTest, ConstantSamplesGiveTheConstantExactly) {
  for (double constant : {3.7, -2.5, 1e-11, -9.9e11}) {
    histogram_.Clear();
    for (int i = 0; i < 1000; ++i) histogram_.Add(constant);
    for (double percent : CheckedPercents()) {
      EXPECT_EQ(histogram_.Percentile(percent), constant) << constant << " at " << percent;
    }
    EXPECT_DOUBLE_EQ(histogram_.mean(), constant);
  }
}

TEST_F(LogHistogramTest, ExactZerosGoToTheZeroBin) {
  for (int i = 0; i < 600; ++i) histogram_.Add(0.0);
  for (int i = 0; i < 200; ++i) histogram_.Add(-0.0);
  for (int i = 0; i < 200; ++i) histogram_.Add(2.0);
  EXPECT_EQ(histogram_.Percentile(1.0), 0.0);
  EXPECT_EQ(histogram_.Percentile(50.0), 0.0);
  EXPECT_EQ(histogram_.Percentile(80.0), 0.0);
  EXPECT_EQ(histogram_.Percentile(80.1), 2.0);
  EXPECT_EQ(histogram_.min(), 0.0);
  EXPECT_EQ(histogram_.max(), 2.0);
  EXPECT_DOUBLE_EQ(histogram_.mean(), 0.4);
}

TEST_F(LogHistogramTest, MixedZerosAndSignedValuesPercentiles) {
  std::normal_distribution<double> normal(0.0, 1e3);
  std::vector<double> samples(kSampleCount);
  for (size_t i = 0; i < samples.size(); ++i) samples[i] = i % 3 == 0 ? 0.0 : normal(rng_);
  AddAndCheckPercentiles(samples);
}

TEST_F(LogHistogramTest, MinMaxSumAndMeanAreExact) {
  std::lognormal_distribution<double> log_normal(0.0, 3.0);
  std::uniform_int_distribution<int> coin(0, 1);
  std::vector<double> samples(kSampleCount);
  long double exact_sum = 0.0L;
  for (double& x : samples) {
    x = (coin(rng_) != 0 ? 1.0 : -1.0) * log_normal(rng_);
    histogram_.Add(x);
    exact_sum += x;
  }
  EXPECT_EQ(histogram_.count(), kSampleCount);
  EXPECT_EQ(histogram_.min(), *std::min_element(samples.begin(), samples.end()));
  EXPECT_EQ(histogram_.max(), *std::max_element(samples.begin(), samples.end()));
  const double sum_of_magnitudes = 1e4 * kSampleCount;  // a generous bound on Σ|x|
  EXPECT_NEAR(histogram_.sum(), static_cast<double>(exact_sum), 1e-15 * sum_of_magnitudes);
  EXPECT_NEAR(histogram_.mean(), static_cast<double>(exact_sum / kSampleCount),
              1e-15 * sum_of_magnitudes / kSampleCount);
}

TEST_F(LogHistogramTest, CompensatedMeanOfTenMillionTenthsIsExact) {
  // Naive summation of 1e7 × 0.1 drifts by ~1.6e-10 relative; the compensated sum does not.
  constexpr int kCount = 10'000'000;
  for (int i = 0; i < kCount; ++i) histogram_.Add(0.1);
  EXPECT_NEAR(histogram_.mean(), 0.1, 1e-16);
  EXPECT_NEAR(histogram_.sum(), 1e6, 1e-9);
}

TEST_F(LogHistogramTest, MergeEqualsOneHistogramOfAllSamples) {
  std::normal_distribution<double> normal(1.0, 5.0);
  LogHistogram first;
  LogHistogram second;
  for (int i = 0; i < kSampleCount; ++i) {
    const double x = normal(rng_);
    histogram_.Add(x);
    (i % 3 == 0 ? first : second).Add(x);
  }
  second.Add(kNaN);
  histogram_.Add(kNaN);
  first.Merge(second);
  EXPECT_EQ(first.count(), histogram_.count());
  EXPECT_EQ(first.nan_count(), histogram_.nan_count());
  EXPECT_EQ(first.min(), histogram_.min());
  EXPECT_EQ(first.max(), histogram_.max());
  EXPECT_NEAR(first.mean(), histogram_.mean(), 1e-15);
  for (double percent = 0.0; percent <= 100.0; percent += 0.25) {
    EXPECT_EQ(first.Percentile(percent), histogram_.Percentile(percent)) << percent;
  }
}

TEST_F(LogHistogramTest, MergeWithItselfDoublesTheCounts) {
  for (double x : {1.0, 2.0, 3.0, kNaN}) histogram_.Add(x);
  histogram_.Merge(histogram_);
  EXPECT_EQ(histogram_.count(), 6);
  EXPECT_EQ(histogram_.nan_count(), 2);
  EXPECT_EQ(histogram_.sum(), 12.0);
  EXPECT_EQ(histogram_.Percentile(50.0), histogram_.Percentile(50.0));
}

TEST_F(LogHistogramTest, MergeIntoAnEmptyHistogramAndFromAnEmptyOne) {
  LogHistogram empty;
  histogram_.Add(-4.0);
  histogram_.Add(8.0);
  histogram_.Merge(empty);
  EXPECT_EQ(histogram_.min(), -4.0);
  EXPECT_EQ(histogram_.max(), 8.0);
  empty.Merge(histogram_);
  EXPECT_EQ(empty.count(), 2);
  EXPECT_EQ(empty.min(), -4.0);
  EXPECT_EQ(empty.mean(), 2.0);
}

TEST_F(LogHistogramTest, MergeRejectsADifferentGeometry) {
  EXPECT_THROW(histogram_.Merge(LogHistogram(1e-9, 1e12, 8)), std::invalid_argument);
  EXPECT_THROW(histogram_.Merge(LogHistogram(1e-12, 1e9, 8)), std::invalid_argument);
  EXPECT_THROW(histogram_.Merge(LogHistogram(1e-12, 1e12, 7)), std::invalid_argument);
}

TEST_F(LogHistogramTest, NaNIsCountedButNotBinned) {
  histogram_.Add(kNaN);
  histogram_.Add(-kNaN);
  histogram_.Add(1.5);
  EXPECT_EQ(histogram_.nan_count(), 2);
  EXPECT_EQ(histogram_.count(), 1);
  EXPECT_EQ(histogram_.min(), 1.5);
  EXPECT_EQ(histogram_.max(), 1.5);
  EXPECT_EQ(histogram_.mean(), 1.5);
  EXPECT_EQ(histogram_.Percentile(50.0), 1.5);
}

TEST_F(LogHistogramTest, EmptyHistogramGivesNaN) {
  EXPECT_TRUE(std::isnan(histogram_.Percentile(50.0)));
  EXPECT_TRUE(std::isnan(histogram_.Percentile(0.0)));
  EXPECT_TRUE(std::isnan(histogram_.min()));
  EXPECT_TRUE(std::isnan(histogram_.max()));
  EXPECT_TRUE(std::isnan(histogram_.mean()));
  EXPECT_EQ(histogram_.sum(), 0.0);
  histogram_.Add(kNaN);  // NaN only: still empty
  EXPECT_TRUE(std::isnan(histogram_.Percentile(50.0)));
}

TEST_F(LogHistogramTest, EdgePercentsAreMinAndMax) {
  for (double x : {-3.3, 0.7, 1.1, 250.0}) histogram_.Add(x);
  EXPECT_EQ(histogram_.Percentile(0.0), -3.3);
  EXPECT_EQ(histogram_.Percentile(100.0), 250.0);
  // The smallest positive percent is rank 1, the largest below 100 is rank n: clamped exactly.
  EXPECT_EQ(histogram_.Percentile(1e-9), -3.3);
  EXPECT_EQ(histogram_.Percentile(100.0 - 1e-9), 250.0);
}

TEST_F(LogHistogramTest, PercentOutsideZeroToHundredThrows) {
  histogram_.Add(1.0);
  EXPECT_THROW(histogram_.Percentile(-1e-9), std::invalid_argument);
  EXPECT_THROW(histogram_.Percentile(100.0 + 1e-9), std::invalid_argument);
  EXPECT_THROW(histogram_.Percentile(kNaN), std::invalid_argument);
}

TEST_F(LogHistogramTest, MagnitudesNearTheRangeEdgesAreAccurate) {
  const double w_rel = histogram_.relative_bin_width();
  std::vector<double> samples;
  for (int i = 0; i < 1000; ++i) {
    samples.push_back(1.0001e-12 * (1.0 + i * 1e-3));  // just above min_magnitude
    samples.push_back(-9.99e11 * (1.0 - i * 1e-4));    // just below -max_magnitude
  }
  for (double x : samples) histogram_.Add(x);
  std::sort(samples.begin(), samples.end());
  for (double percent : {10.0, 25.0, 40.0, 60.0, 75.0, 90.0}) {
    const double exact = ExactPercentile(samples, percent);
    EXPECT_LT(std::abs(histogram_.Percentile(percent) - exact), w_rel * std::abs(exact))
        << percent;
  }
}

TEST_F(LogHistogramTest, OutOfRangeMagnitudesAreCountedAndBounded) {
  histogram_.Add(1e-20);   // zero bin
  histogram_.Add(-1e-300);  // zero bin
  histogram_.Add(std::numeric_limits<double>::denorm_min());  // zero bin
  histogram_.Add(1.0);
  histogram_.Add(1e30);  // outermost positive bin
  histogram_.Add(kInf);  // outermost positive bin
  histogram_.Add(-1e200);  // outermost negative bin
  EXPECT_EQ(histogram_.count(), 7);
  EXPECT_EQ(histogram_.min(), -1e200);
  EXPECT_EQ(histogram_.max(), kInf);
  EXPECT_EQ(histogram_.Percentile(0.0), -1e200);
  EXPECT_EQ(histogram_.Percentile(100.0), kInf);
  // Rank 2 … 4 (percent 20 … 57) are the zero bin: 0 within min_magnitude.
  EXPECT_EQ(histogram_.Percentile(20.0), 0.0);
  EXPECT_EQ(histogram_.Percentile(57.0), 0.0);
  EXPECT_NEAR(histogram_.Percentile(58.0), 1.0, histogram_.relative_bin_width());
  // Beyond max_magnitude: at least the outermost bin's lower edge.
  EXPECT_GE(histogram_.Percentile(80.0), 0.99e12);
  EXPECT_LE(histogram_.Percentile(5.0), -0.99e12);
  EXPECT_EQ(histogram_.sum(), kInf);
  histogram_.Add(-kInf);
  EXPECT_TRUE(std::isnan(histogram_.sum()));
}

TEST_F(LogHistogramTest, ClearForgetsEverything) {
  for (double x : {1.0, -2.0, kNaN}) histogram_.Add(x);
  histogram_.Clear();
  EXPECT_EQ(histogram_.count(), 0);
  EXPECT_EQ(histogram_.nan_count(), 0);
  EXPECT_TRUE(std::isnan(histogram_.Percentile(50.0)));
  histogram_.Add(5.0);
  EXPECT_EQ(histogram_.Percentile(50.0), 5.0);
  EXPECT_EQ(histogram_.mean(), 5.0);
}

TEST_F(LogHistogramTest, DefaultGeometryIsSmall) {
  // 1e-12 … 1e12 is ~80 octaves × 256 bins per sign: ~41 k counters, ~330 KiB.
  EXPECT_GT(histogram_.bin_count(), 40'000);
  EXPECT_LT(histogram_.bin_count(), 42'000);
  EXPECT_EQ(histogram_.relative_bin_width(), 1.0 / 256.0);
}

TEST(LogHistogramConstructorTest, RejectsBadArguments) {
  EXPECT_THROW(LogHistogram(0.0, 1.0, 8), std::invalid_argument);
  EXPECT_THROW(LogHistogram(-1.0, 1.0, 8), std::invalid_argument);
  EXPECT_THROW(LogHistogram(1e-310, 1.0, 8), std::invalid_argument);  // subnormal
  EXPECT_THROW(LogHistogram(kNaN, 1.0, 8), std::invalid_argument);
  EXPECT_THROW(LogHistogram(1.0, 1.0, 8), std::invalid_argument);
  EXPECT_THROW(LogHistogram(1.0, 0.5, 8), std::invalid_argument);
  EXPECT_THROW(LogHistogram(1.0, kInf, 8), std::invalid_argument);
  EXPECT_THROW(LogHistogram(1e-12, 1e12, 0), std::invalid_argument);
  EXPECT_THROW(LogHistogram(1e-12, 1e12, LogHistogram::kMaxSubBucketBits + 1),
               std::invalid_argument);
  EXPECT_THROW(LogHistogram(1e-300, 1e300, 20), std::invalid_argument);  // too many bins
  EXPECT_NO_THROW(LogHistogram(1e-3, 1e3, 12));
}

TEST(LogHistogramConstructorTest, FinerBinsAreMoreAccurate) {
  LogHistogram fine(1e-6, 1e6, 14);
  std::mt19937_64 rng(7);
  std::exponential_distribution<double> exponential(1.0);
  std::vector<double> samples(20'000);
  for (double& x : samples) {
    x = exponential(rng);
    fine.Add(x);
  }
  std::sort(samples.begin(), samples.end());
  for (double percent : {1.0, 50.0, 99.0}) {
    const double exact = ExactPercentile(samples, percent);
    EXPECT_LT(std::abs(fine.Percentile(percent) - exact), std::ldexp(exact, -14)) << percent;
  }
}

}  // namespace
}  // namespace dpc

namespace dpc {
namespace {

TEST(LogHistogramBatchTest, AddBatchEqualsAddOneByOne) {
  std::mt19937_64 rng(4);
  std::normal_distribution<double> normal(0.0, 3.0);
  std::vector<double> values(1000);
  for (auto& v : values) v = normal(rng);
  values[17] = NAN;
  values[18] = 0.0;
  LogHistogram one, batch, strided;
  for (double v : values) one.Add(v);
  batch.AddBatch(values.data(), 600);
  batch.AddBatch(values.data() + 600, 400);
  std::vector<double> interleaved;
  for (double v : values) {
    interleaved.push_back(v);
    interleaved.push_back(99.0);  // the other column
  }
  strided.AddBatch(interleaved.data(), 1000, 2);
  for (const LogHistogram* h : {&batch, &strided}) {
    EXPECT_EQ(h->count(), one.count());
    EXPECT_EQ(h->nan_count(), one.nan_count());
    EXPECT_EQ(h->min(), one.min());
    EXPECT_EQ(h->max(), one.max());
    EXPECT_NEAR(h->sum(), one.sum(), 1e-12 * std::abs(one.sum()) + 1e-12);
    for (double p : {1.0, 50.0, 99.0}) EXPECT_EQ(h->Percentile(p), one.Percentile(p));
  }
}

TEST(LogHistogramBatchTest, AddBatchLanesEqualsAddOneByOnePerColumn) {
  std::mt19937_64 rng(6);
  std::normal_distribution<double> normal(0.0, 2.0);
  constexpr int kRows = 700;  // more than one chunk, not a multiple of four
  std::vector<double> rows(4 * kRows);
  for (auto& v : rows) v = normal(rng);
  rows[4 * 17 + 1] = NAN;
  rows[4 * 18 + 2] = 0.0;
  rows[4 * 19 + 0] = -1e-20;  // below the smallest binned magnitude
  rows[4 * 20 + 2] = 1e30;    // beyond the largest
  rows[4 * 21 + 3] = 5.0;     // the ignored column of a 3-lane call
  for (int lanes : {3, 4}) {
    std::vector<LogHistogram> one(4), lane(4);
    LogHistogram* histograms[4] = {&lane[0], &lane[1], &lane[2], &lane[3]};
    for (int c = 0; c < lanes; ++c) {
      one[c].Add(0.25);  // earlier samples: the batch continues them
      lane[c].Add(0.25);
      for (int i = 0; i < kRows; ++i) one[c].Add(rows[4 * i + c]);
    }
    LogHistogram::AddBatchLanes(histograms, lanes, rows.data(), 500);
    LogHistogram::AddBatchLanes(histograms, lanes, rows.data() + 4 * 500, kRows - 500);
    for (int c = 0; c < lanes; ++c) {
      EXPECT_EQ(lane[c].count(), one[c].count()) << c;
      EXPECT_EQ(lane[c].nan_count(), one[c].nan_count()) << c;
      EXPECT_EQ(lane[c].min(), one[c].min()) << c;
      EXPECT_EQ(lane[c].max(), one[c].max()) << c;
      EXPECT_NEAR(lane[c].sum(), one[c].sum(), 1e-12 * std::abs(one[c].sum()) + 1e-12) << c;
      for (double p : {0.0, 1.0, 50.0, 99.0, 100.0}) {
        EXPECT_EQ(lane[c].Percentile(p), one[c].Percentile(p)) << c << " " << p;
      }
    }
    EXPECT_EQ(lane[3].count(), lanes == 4 ? one[3].count() : 0);
  }
}

TEST(LogHistogramBatchTest, AddBatchLanes8EqualsAddBatchLanesBitForBitPerColumn) {
  // Eight columns in one vector: each column's count, extremes, sum and bins are the four-wide
  // call's exactly (a batch's lanes must equal the scalar simulator's to the bit).
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 2.0);
  constexpr int kRows = 700;
  std::vector<double> rows(8 * kRows);
  for (auto& v : rows) v = normal(rng);
  rows[8 * 17 + 5] = NAN;
  rows[8 * 18 + 6] = 0.0;
  rows[8 * 19 + 4] = -1e-20;
  rows[8 * 20 + 7] = 1e30;
  rows[8 * 21 + 7] = -INFINITY;
  for (int lanes : {5, 8}) {
    std::vector<LogHistogram> wide(8), narrow(8);
    LogHistogram* wide_histograms[8] = {};
    for (int c = 0; c < 8; ++c) wide_histograms[c] = &wide[c];
    for (int c = 0; c < lanes; ++c) {
      wide[c].Add(0.25);
      narrow[c].Add(0.25);
    }
    LogHistogram::AddBatchLanes8(wide_histograms, lanes, rows.data(), 500);
    LogHistogram::AddBatchLanes8(wide_histograms, lanes, rows.data() + 8 * 500, kRows - 500);
    for (int from = 0; from < lanes; from += 4) {
      LogHistogram* narrow_histograms[4] = {&narrow[from], &narrow[from + 1], &narrow[from + 2],
                                            &narrow[from + 3]};
      const int columns = std::min(4, lanes - from);
      LogHistogram::AddBatchLanes(narrow_histograms, columns, rows.data() + from, 500, 8);
      LogHistogram::AddBatchLanes(narrow_histograms, columns, rows.data() + from + 8 * 500,
                                  kRows - 500, 8);
    }
    for (int c = 0; c < 8; ++c) {
      EXPECT_EQ(wide[c].count(), narrow[c].count()) << c;
      EXPECT_EQ(wide[c].nan_count(), narrow[c].nan_count()) << c;
      if (c >= lanes) {
        EXPECT_EQ(wide[c].count(), 0) << c;
        continue;
      }
      EXPECT_EQ(wide[c].count(), kRows + 1 - (c == 5 ? 1 : 0)) << c;
      EXPECT_EQ(std::bit_cast<uint64_t>(wide[c].min()), std::bit_cast<uint64_t>(narrow[c].min())) << c;
      EXPECT_EQ(std::bit_cast<uint64_t>(wide[c].max()), std::bit_cast<uint64_t>(narrow[c].max())) << c;
      EXPECT_EQ(std::bit_cast<uint64_t>(wide[c].sum()), std::bit_cast<uint64_t>(narrow[c].sum())) << c;
      for (double p : {0.0, 1.0, 50.0, 99.0, 100.0}) {
        EXPECT_EQ(wide[c].Percentile(p), narrow[c].Percentile(p)) << c << " " << p;
      }
    }
  }
}

}  // namespace
}  // namespace dpc
