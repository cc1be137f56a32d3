#include "dpc/disturbance/paper_scrambler.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "dpc/optics/rotation.h"

namespace dpc {
namespace {

// The paper's scenario: 100 krad/s about S3, kicks about S2, 50 MHz.
class PaperScramblerTest : public ::testing::Test {
 protected:
  static constexpr double kRateRadPerS = 1e5;
  static constexpr double kSampleRateHz = 50e6;
  static constexpr double kStepRad = kRateRadPerS / kSampleRateHz;  // 2 mrad

  PaperScrambler Paper(double kick_rms_ratio) const {
    return PaperScrambler(kRateRadPerS, kick_rms_ratio, Vector3::UnitZ(), Vector3::UnitY(),
                          kSampleRateHz);
  }

  /// The signed angle of the rotation about unit `axis` that takes `from` to `to`, both
  /// projected on the plane normal to `axis`.
  static double AngleAbout(const Vector3& axis, const Vector3& from, const Vector3& to) {
    const Vector3 a = from - axis.dot(from) * axis, b = to - axis.dot(to) * axis;
    return std::atan2(axis.dot(a.cross(b)), a.dot(b));
  }

  RandomSource random_{2024, 1};
};

TEST_F(PaperScramblerTest, WithoutKicksItIsTheRotationAboutS3) {
  PaperScrambler scrambler = Paper(0.0);
  const StokesVector initial = StokesVector(0.48, 0.6, 0.64);
  StokesVector sop = initial;
  constexpr int kSamples = 1000;
  for (int k = 0; k < kSamples; ++k) scrambler.Advance(k / kSampleRateHz, &sop, random_);
  const StokesVector expected =
      RotationAboutAxis(Vector3::UnitZ(), kStepRad * kSamples) * initial;
  EXPECT_LT((sop - expected).norm(), 1e-12);
  // Nothing was drawn.
  RandomSource fresh(2024, 1);
  EXPECT_EQ(random_.Normal(), fresh.Normal());
}

TEST_F(PaperScramblerTest, DefaultKickSigmaIsOneStep) {
  EXPECT_DOUBLE_EQ(Paper(1.0).kick_sigma_rad(), kStepRad);
  EXPECT_DOUBLE_EQ(Paper(0.5).kick_sigma_rad(), 0.5 * kStepRad);
}

TEST_F(PaperScramblerTest, EachKickIsARotationAboutS2WithTheRightDistribution) {
  // Decompose each sample: u = R3(ω·dt)·S_prev is known, and S_next = R2(δ)·u, so δ is the
  // angle about S2 from u to S_next. Samples where u is within ~17° of ±S2 (lever arm < 0.3)
  // are skipped; that choice depends on u only, not on δ, so it does not bias δ.
  PaperScrambler scrambler = Paper(1.0);
  const Matrix3 step = R3(kStepRad);
  StokesVector sop = StokesVector::UnitX();
  double sum = 0, sum2 = 0, sum4 = 0, worst_off_axis = 0;
  int used = 0;
  for (int k = 0; k < 400000; ++k) {
    const StokesVector rotated = step * sop;
    scrambler.Advance(k / kSampleRateHz, &sop, random_);
    // S_next − R2(δ)u has no S2 component to check: δ moves u only in the S3–S1 plane.
    worst_off_axis = std::max(worst_off_axis, std::abs(sop.y() - rotated.y()));
    if (1.0 - rotated.y() * rotated.y() < 0.09) continue;
    const double delta = AngleAbout(Vector3::UnitY(), rotated, sop);
    sum += delta;
    sum2 += delta * delta;
    sum4 += delta * delta * delta * delta;
    ++used;
  }
  ASSERT_GT(used, 100000);
  EXPECT_LT(worst_off_axis, 1e-15);
  const double n = used, sigma = kStepRad;
  // SE: mean σ/√n; variance σ²·√(2/n); fourth moment 3σ⁴ (Gaussian), SE σ⁴·√96/√n.
  EXPECT_NEAR(sum / n, 0.0, 6.0 * sigma / std::sqrt(n));
  EXPECT_NEAR(sum2 / n, sigma * sigma, 6.0 * sigma * sigma * std::sqrt(2.0 / n));
  EXPECT_NEAR(sum4 / n, 3.0 * std::pow(sigma, 4), 6.0 * std::pow(sigma, 4) * std::sqrt(96.0 / n));
}

TEST_F(PaperScramblerTest, AccumulatedKicksAreARandomWalkWithSigmaRootN) {
  // With the rotation and the kicks about the same axis S2 the angles add: after N samples
  // from S3 the SOP is R2(ω·dt·N + Σδ)·S3, and Σδ ~ N(0, N·σ²).
  PaperScrambler scrambler(kRateRadPerS, 1.0, Vector3::UnitY(), Vector3::UnitY(), kSampleRateHz);
  constexpr int kRuns = 10000, kSamplesPerRun = 100;
  double sum = 0, sum2 = 0;
  for (int run = 0; run < kRuns; ++run) {
    StokesVector sop = StokesVector::UnitZ();
    for (int k = 0; k < kSamplesPerRun; ++k) scrambler.Advance(k / kSampleRateHz, &sop, random_);
    const double kick_sum = std::atan2(sop.x(), sop.z()) - kStepRad * kSamplesPerRun;
    sum += kick_sum;
    sum2 += kick_sum * kick_sum;
  }
  const double variance = kSamplesPerRun * kStepRad * kStepRad;
  // SE: mean √(variance/runs); variance √(2/runs)·variance (1.4 %).
  EXPECT_NEAR(sum / kRuns, 0.0, 6.0 * std::sqrt(variance / kRuns));
  EXPECT_NEAR(sum2 / kRuns / variance, 1.0, 6.0 * std::sqrt(2.0 / kRuns));
}

TEST_F(PaperScramblerTest, StaysUnitOverAMillionSamples) {
  // Each step is a rotation to round-off, but the same rounded matrix applied 1e6 times lets
  // |S| drift systematically (measured: 1.1e-11 here), bounded by ~1e6·1e-16. The input
  // generator renormalizes every sample (RenormalizeNearUnit), which holds |S| at 1.
  PaperScrambler scrambler = Paper(1.0);
  StokesVector raw = StokesVector(0.0, 0.6, 0.8), renormalized = raw;
  RandomSource random_copy = random_;
  double worst_step_error = 0;
  for (int k = 0; k < 1000000; ++k) {
    const double before = raw.norm();
    scrambler.Advance(k / kSampleRateHz, &raw, random_);
    worst_step_error = std::max(worst_step_error, std::abs(raw.norm() - before));
    scrambler.Advance(k / kSampleRateHz, &renormalized, random_copy);
    RenormalizeNearUnit(&renormalized);
  }
  EXPECT_LT(worst_step_error, 1e-15);
  EXPECT_NEAR(raw.norm(), 1.0, 1e-10);
  EXPECT_NEAR(renormalized.norm(), 1.0, 1e-12);
  // Renormalization changes the trajectory only at round-off level.
  EXPECT_LT((renormalized - raw / raw.norm()).norm(), 1e-9);
}

TEST_F(PaperScramblerTest, SameSeedGivesTheSameTrajectory) {
  PaperScrambler a = Paper(1.0), b = Paper(1.0);
  RandomSource random_a(7, 1), random_b(7, 1);
  StokesVector sop_a = StokesVector::UnitX(), sop_b = sop_a;
  for (int k = 0; k < 10000; ++k) {
    a.Advance(k / kSampleRateHz, &sop_a, random_a);
    b.Advance(k / kSampleRateHz, &sop_b, random_b);
    ASSERT_EQ(sop_a, sop_b) << "sample " << k;
  }
}

TEST_F(PaperScramblerTest, AxesAreNormalized) {
  const PaperScrambler scrambler(kRateRadPerS, 1.0, Vector3(0, 0, 2), Vector3(0, 3, 4),
                                 kSampleRateHz);
  EXPECT_LT((scrambler.rotation_axis() - Vector3::UnitZ()).norm(), 1e-15);
  EXPECT_LT((scrambler.kick_axis() - Vector3(0, 0.6, 0.8)).norm(), 1e-15);
}

TEST_F(PaperScramblerTest, DescribeNamesTheRateAndAxes) {
  const std::string text = Paper(1.0).Describe();
  EXPECT_NE(text.find("paper scrambler"), std::string::npos);
  EXPECT_NE(text.find("100000 rad/s"), std::string::npos);
  EXPECT_NE(text.find("[0, 0, 1]"), std::string::npos);
}

TEST_F(PaperScramblerTest, RejectsNegativeRate) {
  EXPECT_THROW(PaperScrambler(-1.0, 1.0, Vector3::UnitZ(), Vector3::UnitY(), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(PaperScramblerTest, RejectsNonFiniteRate) {
  EXPECT_THROW(PaperScrambler(NAN, 1.0, Vector3::UnitZ(), Vector3::UnitY(), kSampleRateHz),
               std::invalid_argument);
}

TEST_F(PaperScramblerTest, RejectsNegativeKickRatio) {
  EXPECT_THROW(PaperScrambler(kRateRadPerS, -0.1, Vector3::UnitZ(), Vector3::UnitY(),
                              kSampleRateHz),
               std::invalid_argument);
}

TEST_F(PaperScramblerTest, RejectsNonFiniteKickRatio) {
  EXPECT_THROW(PaperScrambler(kRateRadPerS, INFINITY, Vector3::UnitZ(), Vector3::UnitY(),
                              kSampleRateHz),
               std::invalid_argument);
}

TEST_F(PaperScramblerTest, RejectsZeroRotationAxis) {
  EXPECT_THROW(PaperScrambler(kRateRadPerS, 1.0, Vector3::Zero(), Vector3::UnitY(),
                              kSampleRateHz),
               std::invalid_argument);
}

TEST_F(PaperScramblerTest, RejectsZeroKickAxis) {
  EXPECT_THROW(PaperScrambler(kRateRadPerS, 1.0, Vector3::UnitZ(), Vector3::Zero(),
                              kSampleRateHz),
               std::invalid_argument);
}

TEST_F(PaperScramblerTest, RejectsNonFiniteAxis) {
  EXPECT_THROW(PaperScrambler(kRateRadPerS, 1.0, Vector3(NAN, 0, 1), Vector3::UnitY(),
                              kSampleRateHz),
               std::invalid_argument);
}

TEST_F(PaperScramblerTest, RejectsBadSampleRate) {
  EXPECT_THROW(PaperScrambler(kRateRadPerS, 1.0, Vector3::UnitZ(), Vector3::UnitY(), 0.0),
               std::invalid_argument);
}

}  // namespace
}  // namespace dpc
