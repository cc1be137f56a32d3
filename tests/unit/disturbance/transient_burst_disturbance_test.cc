#include "dpc/disturbance/transient_burst_disturbance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <stdexcept>
#include <vector>

namespace dpc {
namespace {

using Envelope = TransientBurstDisturbance::Envelope;

class TransientBurstDisturbanceTest : public ::testing::Test {
 protected:
  static constexpr double kSampleRateHz = 50e6;
  static constexpr double kSamplePeriodS = 1.0 / kSampleRateHz;

  /// The rotation angle of each sample about unit `axis` for a SOP kept normal to it, samples
  /// [0, samples). The SOP starts at `start` (normal to `axis`).
  std::vector<double> StepAngles(TransientBurstDisturbance& burst, const Vector3& axis,
                                 const StokesVector& start, int samples) {
    std::vector<double> angles;
    StokesVector sop = start;
    for (int k = 0; k < samples; ++k) {
      const StokesVector before = sop;
      burst.Advance(k * kSamplePeriodS, &sop, random_);
      angles.push_back(std::atan2(axis.dot(before.cross(sop)), before.dot(sop)));
    }
    return angles;
  }

  /// The sum of values[begin, end), end clamped to the size (−1: to the end).
  static double Sum(const std::vector<double>& values, int begin = 0, int end = -1) {
    const int size = static_cast<int>(values.size());
    const int stop = (end < 0 || end > size) ? size : end;
    return std::accumulate(values.begin() + begin, values.begin() + stop, 0.0);
  }

  RandomSource random_{77, 1};
};

TEST_F(TransientBurstDisturbanceTest, NoChangeAndNoDrawsOutsideBursts) {
  // Bursts [10, 15) µs and [30, 35) µs, … ; samples are 20 ns.
  TransientBurstDisturbance burst(10e-6, 5e-6, 1e6, 20e-6, Envelope::kRectangular, std::nullopt,
                                  kSampleRateHz);
  StokesVector sop = StokesVector(0.0, 0.6, 0.8);
  for (int k = 0; k < 2000; ++k) {  // 0 … 40 µs: bursts 0 (samples 500–749) and 1 (1500–1749)
    const StokesVector before = sop;
    burst.Advance(k * kSamplePeriodS, &sop, random_);
    const int phase = k % 1000;
    if (phase >= 500 && phase < 750) {
      ASSERT_GT((sop - before).norm(), 0.0) << "sample " << k;
    } else if (phase != 499 && phase != 750) {
      // (At the edge samples 499 and 750 the rounding of k·dt may leave a sliver of overlap.)
      ASSERT_EQ(sop, before) << "sample " << k;
    }
  }
  // Exactly one UnitVector per burst was drawn.
  RandomSource expected(77, 1);
  expected.UnitVector();
  expected.UnitVector();
  EXPECT_EQ(random_.Uniform(), expected.Uniform());
}

TEST_F(TransientBurstDisturbanceTest, RectangularBurstTurnsByPeakTimesDuration) {
  // A duration that is not a whole number of samples and a start between samples.
  constexpr double kStartS = 1.01e-6, kDurationS = 2.345e-6, kPeakRadPerS = 1e6;
  TransientBurstDisturbance burst(kStartS, kDurationS, kPeakRadPerS, 0.0,
                                  Envelope::kRectangular, Vector3::UnitX(), kSampleRateHz);
  const std::vector<double> angles =
      StepAngles(burst, Vector3::UnitX(), StokesVector::UnitY(), 500);  // 10 µs
  EXPECT_NEAR(Sum(angles), kPeakRadPerS * kDurationS, 1e-12);
  // Full samples inside the burst turn by peak·dt.
  EXPECT_NEAR(angles[100], kPeakRadPerS * kSamplePeriodS, 1e-14);
}

TEST_F(TransientBurstDisturbanceTest, HalfSineBurstTurnsByPeakTimesDurationTimesTwoOverPi) {
  constexpr double kStartS = 2e-6, kDurationS = 4.321e-6, kPeakRadPerS = 5e6;  // lightning
  TransientBurstDisturbance burst(kStartS, kDurationS, kPeakRadPerS, 0.0, Envelope::kHalfSine,
                                  Vector3(1.0, 1.0, 0.0), kSampleRateHz);
  const Vector3 axis = Vector3(1.0, 1.0, 0.0).normalized();
  const std::vector<double> angles =
      StepAngles(burst, axis, StokesVector::UnitZ(), 500);
  // 13.76 rad in total: more than 2π, so the per-sample angles are summed.
  EXPECT_NEAR(Sum(angles), kPeakRadPerS * kDurationS * 2.0 / M_PI, 1e-11);
  // The rate peaks mid-burst: sample at 2 + 4.321/2 µs ≈ sample 208.
  const int middle = static_cast<int>((kStartS + 0.5 * kDurationS) * kSampleRateHz);
  EXPECT_NEAR(angles[middle], kPeakRadPerS * kSamplePeriodS, 1e-3 * kPeakRadPerS * kSamplePeriodS);
  // And is near zero at the edges.
  EXPECT_LT(angles[100], 0.01 * kPeakRadPerS * kSamplePeriodS);
  EXPECT_NEAR(angles[98], 0.0, 1e-15);
}

TEST_F(TransientBurstDisturbanceTest, BurstShorterThanASampleStillActs) {
  TransientBurstDisturbance burst(1.005e-6, 5e-9, 1e6, 0.0, Envelope::kRectangular,
                                  Vector3::UnitZ(), kSampleRateHz);
  const std::vector<double> angles = StepAngles(burst, Vector3::UnitZ(), StokesVector::UnitX(), 100);
  EXPECT_NEAR(Sum(angles), 1e6 * 5e-9, 1e-15);
  EXPECT_GT(angles[50], 0.0);  // the sample [1.000, 1.020) µs holds the whole burst
}

TEST_F(TransientBurstDisturbanceTest, PeriodicBurstsRepeat) {
  // Bursts of 3 µs every 10 µs (500 samples) from 1 µs.
  TransientBurstDisturbance burst(1e-6, 3e-6, 2e6, 10e-6, Envelope::kHalfSine, Vector3::UnitZ(),
                                  kSampleRateHz);
  const std::vector<double> angles = StepAngles(burst, Vector3::UnitZ(), StokesVector::UnitX(), 1500);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(Sum(angles, 500 * k, 500 * (k + 1)), 2e6 * 3e-6 * 2.0 / M_PI, 1e-11)
        << "burst " << k;
  }
  for (int i = 0; i < 500; ++i) {
    ASSERT_NEAR(angles[500 + i], angles[i], 1e-9 * 2e6 * kSamplePeriodS) << "sample " << i;
    ASSERT_NEAR(angles[1000 + i], angles[i], 1e-9 * 2e6 * kSamplePeriodS) << "sample " << i;
  }
}

TEST_F(TransientBurstDisturbanceTest, SingleBurstHappensOnce) {
  TransientBurstDisturbance burst(1e-6, 1e-6, 1e6, 0.0, Envelope::kRectangular, Vector3::UnitZ(),
                                  kSampleRateHz);
  const std::vector<double> angles = StepAngles(burst, Vector3::UnitZ(), StokesVector::UnitX(), 1000);
  EXPECT_NEAR(Sum(angles, 0, 100), 1.0, 1e-12);
  EXPECT_NEAR(Sum(angles, 100), 0.0, 1e-12);  // (a rounding sliver at most)
  EXPECT_EQ(Sum(angles, 101), 0.0);
}

TEST_F(TransientBurstDisturbanceTest, RandomAxisChangesBetweenBurstsAndHoldsWithinOne) {
  TransientBurstDisturbance burst(1e-6, 2e-6, 1e6, 5e-6, Envelope::kRectangular, std::nullopt,
                                  kSampleRateHz);
  EXPECT_TRUE(burst.random_axis());
  std::vector<Vector3> axes;
  StokesVector sop = StokesVector::UnitX();
  Vector3 axis_at_burst_start = Vector3::Zero();
  for (int k = 0; k < 1000; ++k) {  // 20 µs: bursts at 1, 6, 11, 16 µs
    const double t_s = k * kSamplePeriodS;
    burst.Advance(t_s, &sop, random_);
    const int64_t index = burst.BurstIndexAt(t_s);
    if (index < 0) continue;
    if (static_cast<size_t>(index) == axes.size()) {
      axes.push_back(burst.current_axis());
      axis_at_burst_start = burst.current_axis();
    }
    ASSERT_EQ(burst.current_axis(), axis_at_burst_start) << "sample " << k;
  }
  ASSERT_EQ(axes.size(), 4u);
  for (size_t i = 0; i < axes.size(); ++i) {
    EXPECT_NEAR(axes[i].norm(), 1.0, 1e-15);
    for (size_t j = 0; j < i; ++j) EXPECT_LT(axes[i].dot(axes[j]), 0.999) << i << ", " << j;
  }
}

TEST_F(TransientBurstDisturbanceTest, BurstIndexAt) {
  const TransientBurstDisturbance periodic(1e-6, 2e-6, 1e6, 5e-6, Envelope::kRectangular,
                                           Vector3::UnitZ(), kSampleRateHz);
  EXPECT_EQ(periodic.BurstIndexAt(0.5e-6), -1);
  EXPECT_EQ(periodic.BurstIndexAt(1e-6), 0);
  EXPECT_EQ(periodic.BurstIndexAt(2.9e-6), 0);
  EXPECT_EQ(periodic.BurstIndexAt(3.5e-6), -1);
  EXPECT_EQ(periodic.BurstIndexAt(6.5e-6), 1);
  EXPECT_EQ(periodic.BurstIndexAt(1e-6 + 1000 * 5e-6 + 1e-6), 1000);
  const TransientBurstDisturbance once(1e-6, 2e-6, 1e6, 0.0, Envelope::kRectangular,
                                       Vector3::UnitZ(), kSampleRateHz);
  EXPECT_EQ(once.BurstIndexAt(2e-6), 0);
  EXPECT_EQ(once.BurstIndexAt(6.5e-6), -1);
}

TEST_F(TransientBurstDisturbanceTest, DescribeNamesTheBurst) {
  const std::string text = TransientBurstDisturbance(1e-3, 1e-4, 5e6, 0.0, Envelope::kHalfSine,
                                                     std::nullopt, kSampleRateHz)
                               .Describe();
  EXPECT_NE(text.find("half-sine"), std::string::npos);
  EXPECT_NE(text.find("5e+06 rad/s"), std::string::npos);
  EXPECT_NE(text.find("random axis"), std::string::npos);
}

TEST_F(TransientBurstDisturbanceTest, RejectsNonFiniteStart) {
  EXPECT_THROW(TransientBurstDisturbance(NAN, 1e-6, 1e6, 0.0, Envelope::kRectangular,
                                         Vector3::UnitZ(), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(TransientBurstDisturbanceTest, RejectsZeroDuration) {
  EXPECT_THROW(TransientBurstDisturbance(0.0, 0.0, 1e6, 0.0, Envelope::kRectangular,
                                         Vector3::UnitZ(), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(TransientBurstDisturbanceTest, RejectsNegativePeakRate) {
  EXPECT_THROW(TransientBurstDisturbance(0.0, 1e-6, -1e6, 0.0, Envelope::kRectangular,
                                         Vector3::UnitZ(), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(TransientBurstDisturbanceTest, RejectsOverlappingBursts) {
  EXPECT_THROW(TransientBurstDisturbance(0.0, 2e-6, 1e6, 1e-6, Envelope::kRectangular,
                                         Vector3::UnitZ(), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(TransientBurstDisturbanceTest, RejectsNegativePeriod) {
  EXPECT_THROW(TransientBurstDisturbance(0.0, 2e-6, 1e6, -5e-6, Envelope::kRectangular,
                                         Vector3::UnitZ(), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(TransientBurstDisturbanceTest, RejectsZeroAxis) {
  EXPECT_THROW(TransientBurstDisturbance(0.0, 2e-6, 1e6, 0.0, Envelope::kRectangular,
                                         Vector3::Zero(), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(TransientBurstDisturbanceTest, RejectsBadSampleRate) {
  EXPECT_THROW(TransientBurstDisturbance(0.0, 2e-6, 1e6, 0.0, Envelope::kRectangular,
                                         Vector3::UnitZ(), 0.0),
               std::invalid_argument);
}

}  // namespace
}  // namespace dpc
