#include "dpc/control/input_predictor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "dpc/disturbance/paper_scrambler.h"
#include "dpc/disturbance/random_source.h"
#include "dpc/optics/rotation.h"

namespace dpc {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Vector3 Unit(double x, double y, double z) { return Vector3(x, y, z).normalized(); }

TEST(InputPredictorTest, PredictsAConstantRotationExactly) {
  // A rotation of 0.02 rad per sample about a general axis (1 Mrad/s at 50 MHz).
  const Vector3 axis = Unit(0.3, -0.4, 0.86);
  const double angle = 0.02;
  const Matrix3 step = RotationAboutAxis(axis, angle);
  InputPredictor predictor(1000);
  StokesVector s = Unit(0.8, 0.5, -0.3);
  for (int k = 0; k < 300; ++k) {
    predictor.Observe(s);
    s = step * s;
  }
  // s is now one sample past the latest: the prediction 1 and 50 samples ahead, exact up to the
  // fit's ridge (1e-9 of tr A, a relative bias of ~2e-9 on the rate here).
  EXPECT_LT((predictor.PredictSamples(1) - s).norm(), 1e-10);
  const StokesVector ahead = RotationAboutAxis(axis, 50 * angle) * predictor.latest();
  EXPECT_LT((predictor.PredictSamples(50) - ahead).norm(), 1e-8);
  EXPECT_LT((predictor.RotationPerSample() - angle * axis).norm(), 1e-10);
}

TEST(InputPredictorTest, PredictsFromIrregularTimestampsInSeconds) {
  // 400 rad/s about S3 sampled at ~10 kHz with jittered times: the time-based API.
  const double rate = 400.0;
  InputPredictor predictor(200, 1e-4);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> jitter(0.5e-4, 1.5e-4);
  const StokesVector start = Unit(0.6, 0.2, 0.77);
  double t = 0.0;
  for (int k = 0; k < 500; ++k) {
    t += jitter(rng);
    ASSERT_TRUE(predictor.ObserveAt(R3(rate * t) * start, t));
  }
  const double horizon_s = 3e-4;
  const StokesVector expected = R3(rate * (t + horizon_s)) * start;
  // The model ρ = (τ/2)·w is exact only for equal intervals: the error is of order θ³ per
  // interval (θ ≤ 0.06 rad), far below a degree.
  EXPECT_LT((predictor.PredictSeconds(horizon_s) - expected).norm(), 1e-4);
  EXPECT_NEAR(predictor.RateRadPerS(), rate, 0.01 * rate);
}

TEST(InputPredictorTest, AStaticInputIsPredictedWhereItIs) {
  InputPredictor predictor(100);
  const StokesVector s = Unit(0.1, 0.9, 0.3);
  for (int k = 0; k < 50; ++k) predictor.Observe(s);
  EXPECT_LT((predictor.PredictSamples(50) - s).norm(), 1e-15);
  EXPECT_EQ(predictor.RotationPerSample().norm(), 0.0);
}

TEST(InputPredictorTest, BeforeTwoSamplesItReturnsTheLatest) {
  InputPredictor predictor(100);
  const StokesVector s = Unit(0.1, 0.9, 0.3);
  predictor.Observe(s);
  EXPECT_LT((predictor.PredictSamples(10) - s).norm(), 1e-15);
}

TEST(InputPredictorTest, IgnoresNonFiniteSamplesAndBackwardTimes) {
  InputPredictor predictor(100, 1e-3);
  EXPECT_TRUE(predictor.ObserveAt(Unit(1, 0, 0), 1.0));
  EXPECT_FALSE(predictor.ObserveAt(StokesVector(kNaN, 0, 0), 2.0));
  EXPECT_FALSE(predictor.ObserveAt(Unit(0, 1, 0), 1.0));   // not after the latest
  EXPECT_FALSE(predictor.ObserveAt(Unit(0, 1, 0), kNaN));
  EXPECT_FALSE(predictor.Observe(StokesVector(0, 0, 0)));
  EXPECT_EQ(predictor.samples(), 1);
  EXPECT_TRUE(predictor.PredictSamples(5).allFinite());
}

TEST(InputPredictorTest, ResetForgetsTheHistory) {
  InputPredictor predictor(100);
  const Matrix3 step = R3(0.01);
  StokesVector s = Unit(1, 0, 0);
  for (int k = 0; k < 20; ++k, s = step * s) predictor.Observe(s);
  predictor.Reset();
  EXPECT_EQ(predictor.samples(), 0);
  predictor.Observe(s);
  EXPECT_LT((predictor.PredictSamples(10) - s).norm(), 1e-15);
}

TEST(InputPredictorTest, ReachesTheFloorOfThePaperScrambler) {
  // The paper's scrambler at 100 krad/s, 50 MHz: σ = 2 mrad per sample. What remains of the
  // prediction error D = 50 samples ahead is the kicks of those samples: ≈ 0.63·σ·√D on average
  // over the orbit (input_predictor.h). The fit over 1000 samples adds little to it.
  const double fs = 50e6, rate = 1e5;
  const int horizon = 50;
  PaperScrambler scrambler(rate, 1.0, Vector3::UnitZ(), Vector3::UnitY(), fs);
  RandomSource random(1, 1);
  InputPredictor predictor(1000);
  const int total = 400000;
  std::vector<StokesVector> history;
  history.reserve(total);
  StokesVector s = Unit(1, 0, 0);
  for (int k = 0; k < total; ++k) {
    scrambler.Advance(0.0, &s, random);
    history.push_back(s);
  }
  double sum_error = 0.0, sum_oracle = 0.0;
  int count = 0;
  const Matrix3 oracle_step = R3(rate / fs * horizon);
  for (int k = 0; k + horizon < total; ++k) {
    predictor.Observe(history[k]);
    if (k < 20000) continue;
    const StokesVector& truth = history[k + horizon];
    sum_error += SphereAngleRad(predictor.PredictSamples(horizon), truth);
    sum_oracle += SphereAngleRad(oracle_step * history[k], truth);  // knows ω exactly
    ++count;
  }
  const double mean_error = sum_error / count, mean_oracle = sum_oracle / count;
  const double floor = 0.63 * (rate / fs) * std::sqrt(horizon);
  EXPECT_NEAR(mean_oracle, floor, 0.25 * floor);
  EXPECT_LT(mean_error, 1.15 * mean_oracle);
  std::printf("prediction error %.3f mrad, oracle %.3f mrad, 0.63·σ·√D = %.3f mrad\n",
              1e3 * mean_error, 1e3 * mean_oracle, 1e3 * floor);
}

TEST(InputPredictorTest, RejectsBadSettings) {
  EXPECT_THROW(InputPredictor{0.0}, std::invalid_argument);
  EXPECT_THROW(InputPredictor{-5.0}, std::invalid_argument);
  EXPECT_THROW(InputPredictor{kNaN}, std::invalid_argument);
  EXPECT_THROW((InputPredictor{100.0, 0.0}), std::invalid_argument);
  EXPECT_THROW((InputPredictor{100.0, std::numeric_limits<double>::infinity()}),
               std::invalid_argument);
}

}  // namespace
}  // namespace dpc
