#include "dpc/disturbance/random_walk_disturbance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace dpc {
namespace {

class RandomWalkDisturbanceTest : public ::testing::Test {
 protected:
  static constexpr double kSampleRateHz = 1e6;
  static constexpr double kSamplePeriodS = 1.0 / kSampleRateHz;

  /// Advances `sop` by `samples` samples of `walk`.
  void Run(RandomWalkDisturbance& walk, int samples, StokesVector* sop) {
    for (int k = 0; k < samples; ++k) walk.Advance(k * kSamplePeriodS, sop, random_);
  }

  RandomSource random_{31337, 1};
};

TEST_F(RandomWalkDisturbanceTest, ZeroDiffusionDoesNothingAndDrawsNothing) {
  RandomWalkDisturbance walk(0.0, kSampleRateHz);
  StokesVector sop(0.0, 0.6, 0.8);
  Run(walk, 1000, &sop);
  EXPECT_EQ(sop, StokesVector(0.0, 0.6, 0.8));
  RandomSource fresh(31337, 1);
  EXPECT_EQ(random_.Normal(), fresh.Normal());
}

TEST_F(RandomWalkDisturbanceTest, StepSigmaIsDRootDt) {
  EXPECT_DOUBLE_EQ(RandomWalkDisturbance(100.0, kSampleRateHz).step_sigma_rad(), 0.1);
}

TEST_F(RandomWalkDisturbanceTest, ShortTimeMeanSquaredDisplacementIsTwoDSquaredT) {
  // D²·t = 1e-5 rad²: small angles, where E[θ²] = 2·D²·t (1 + O(D²·t)).
  constexpr double kDiffusion = 1.0;  // rad/√s
  constexpr int kSamples = 10, kRuns = 20000;
  RandomWalkDisturbance walk(kDiffusion, kSampleRateHz);
  double sum = 0;
  for (int run = 0; run < kRuns; ++run) {
    const StokesVector initial = random_.UnitVector();
    StokesVector sop = initial;
    Run(walk, kSamples, &sop);
    const double angle = SphereAngleRad(initial, sop);
    sum += angle * angle;
  }
  const double expected = 2.0 * kDiffusion * kDiffusion * kSamples * kSamplePeriodS;
  // θ² ≈ σ²·χ²₂: its standard deviation equals its mean; SE 1/√runs ≈ 0.7 %.
  EXPECT_NEAR(sum / kRuns / expected, 1.0, 6.0 / std::sqrt(kRuns));
}

TEST_F(RandomWalkDisturbanceTest, MeanCosineDecaysExactlyAsLambdaToTheN) {
  // E[S_N·S_0] = λ^N, λ = 1/3 + (2/3)(1 − σ²)·exp(−σ²/2), σ² = D²·dt; ≈ 0.5 here.
  constexpr double kDiffusion = 83.0;
  constexpr int kSamples = 100, kRuns = 20000;
  RandomWalkDisturbance walk(kDiffusion, kSampleRateHz);
  const double sigma2 = kDiffusion * kDiffusion * kSamplePeriodS;
  const double lambda = 1.0 / 3.0 + 2.0 / 3.0 * (1.0 - sigma2) * std::exp(-0.5 * sigma2);
  double sum = 0, sum2 = 0;
  for (int run = 0; run < kRuns; ++run) {
    const StokesVector initial = random_.UnitVector();
    StokesVector sop = initial;
    Run(walk, kSamples, &sop);
    const double cosine = initial.dot(sop);
    sum += cosine;
    sum2 += cosine * cosine;
  }
  const double mean = sum / kRuns;
  const double standard_error = std::sqrt((sum2 / kRuns - mean * mean) / kRuns);
  EXPECT_NEAR(mean, std::pow(lambda, kSamples), 6.0 * standard_error);
  EXPECT_NEAR(std::pow(lambda, kSamples), std::exp(-kDiffusion * kDiffusion * kSamples *
                                                   kSamplePeriodS), 1e-3);
}

TEST_F(RandomWalkDisturbanceTest, RotationVectorIsIsotropic) {
  // One small step from S3 moves the SOP by ≈ (v2, −v1) in (S1, S2); from S1 by ≈ (v3, −v2) in
  // (S2, S3). Every component of v must have variance σ² = D²·dt and they must be uncorrelated.
  constexpr double kDiffusion = 1.0;
  constexpr int kSteps = 100000;
  RandomWalkDisturbance walk(kDiffusion, kSampleRateHz);
  const double sigma2 = kDiffusion * kDiffusion * kSamplePeriodS;
  const StokesVector starts[] = {StokesVector::UnitZ(), StokesVector::UnitX()};
  for (const StokesVector& start : starts) {
    const int a = start.z() == 1.0 ? 0 : 1;  // the two tangent components
    const int b = a + 1;
    double sum_a = 0, sum_b = 0, sum_aa = 0, sum_bb = 0, sum_ab = 0;
    for (int k = 0; k < kSteps; ++k) {
      StokesVector sop = start;
      walk.Advance(0.0, &sop, random_);
      sum_a += sop[a];
      sum_b += sop[b];
      sum_aa += sop[a] * sop[a];
      sum_bb += sop[b] * sop[b];
      sum_ab += sop[a] * sop[b];
    }
    const double n = kSteps;
    // SE: mean σ/√n; variance σ²·√(2/n) (0.45 %); covariance σ²/√n.
    const double sigma = std::sqrt(sigma2);
    EXPECT_NEAR(sum_a / n, 0.0, 6.0 * sigma / std::sqrt(n));
    EXPECT_NEAR(sum_b / n, 0.0, 6.0 * sigma / std::sqrt(n));
    EXPECT_NEAR(sum_aa / n / sigma2, 1.0, 6.0 * std::sqrt(2.0 / n));
    EXPECT_NEAR(sum_bb / n / sigma2, 1.0, 6.0 * std::sqrt(2.0 / n));
    EXPECT_NEAR(sum_ab / n / sigma2, 0.0, 6.0 / std::sqrt(n));
  }
}

TEST_F(RandomWalkDisturbanceTest, EveryStepIsARotation) {
  RandomWalkDisturbance walk(1000.0, kSampleRateHz);  // 1 rad per component per sample
  StokesVector sop = StokesVector::UnitX();
  for (int k = 0; k < 100000; ++k) {
    walk.Advance(k * kSamplePeriodS, &sop, random_);
    ASSERT_NEAR(sop.norm(), 1.0, 1e-12) << "sample " << k;
  }
}

TEST_F(RandomWalkDisturbanceTest, SameSeedGivesTheSameTrajectory) {
  RandomWalkDisturbance walk(50.0, kSampleRateHz);
  RandomSource a(3, 1), b(3, 1);
  StokesVector sop_a = StokesVector::UnitY(), sop_b = sop_a;
  for (int k = 0; k < 10000; ++k) {
    walk.Advance(k * kSamplePeriodS, &sop_a, a);
    walk.Advance(k * kSamplePeriodS, &sop_b, b);
    ASSERT_EQ(sop_a, sop_b);
  }
}

TEST_F(RandomWalkDisturbanceTest, DescribeNamesTheDiffusion) {
  EXPECT_NE(RandomWalkDisturbance(50.0, kSampleRateHz).Describe().find("D = 50 rad/sqrt(s)"),
            std::string::npos);
}

TEST_F(RandomWalkDisturbanceTest, RejectsNegativeDiffusion) {
  EXPECT_THROW(RandomWalkDisturbance(-1.0, kSampleRateHz), std::invalid_argument);
}

TEST_F(RandomWalkDisturbanceTest, RejectsNonFiniteDiffusion) {
  EXPECT_THROW(RandomWalkDisturbance(NAN, kSampleRateHz), std::invalid_argument);
}

TEST_F(RandomWalkDisturbanceTest, RejectsBadSampleRate) {
  EXPECT_THROW(RandomWalkDisturbance(1.0, -5.0), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
