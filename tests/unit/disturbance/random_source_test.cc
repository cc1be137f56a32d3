#include "dpc/disturbance/random_source.h"

#include <gtest/gtest.h>

#include <bit>
#include <boost/random/mersenne_twister.hpp>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

namespace dpc {
namespace {

// Statistical tests use fixed seeds, so they are deterministic; their tolerances are still
// several standard errors (SE) so that a change of seed or engine would not make them flake.

TEST(SplitMix64Test, MixMatchesTheReferenceSequence) {
  // SplitMix64 seeded with 1234567 (reference implementation, Vigna's splitmix64.c): its
  // outputs are Mix64(seed + n·γ), n = 1, 2, 3.
  constexpr uint64_t kGamma = 0x9e3779b97f4a7c15ULL;
  EXPECT_EQ(SplitMix64Mix(1234567 + kGamma), 6457827717110365317ULL);
  EXPECT_EQ(SplitMix64Mix(1234567 + 2 * kGamma), 3203168211198807973ULL);
  EXPECT_EQ(SplitMix64Mix(1234567 + 3 * kGamma), 9817491932198370423ULL);
}

TEST(SplitMix64Test, EngineSeedsAreTheDocumentedDerivation) {
  // Values computed independently (Python) from Mix64(Mix64(seed + γ) + γ·(stream + 1)).
  EXPECT_EQ(DeriveEngineSeed(7, 0), 13309476754707697221ULL);
  EXPECT_EQ(DeriveEngineSeed(7, 1), 11984929618412882174ULL);
  EXPECT_EQ(DeriveEngineSeed(7, 2), 10134167572453724827ULL);
}

TEST(SplitMix64Test, EngineSeedsAreDistinctOverSeedsAndStreams) {
  std::set<uint64_t> seeds;
  for (uint64_t seed = 0; seed < 64; ++seed) {
    for (uint64_t stream = 0; stream < 8; ++stream) seeds.insert(DeriveEngineSeed(seed, stream));
  }
  EXPECT_EQ(seeds.size(), 64u * 8u);
}

class RandomSourceTest : public ::testing::Test {
 protected:
  static constexpr int kSamples = 1000000;
  RandomSource random_{12345, 0};
};

TEST_F(RandomSourceTest, SameSeedAndStreamGiveTheSameSequence) {
  RandomSource a(99, 3), b(99, 3);
  EXPECT_EQ(a.seed(), 99u);
  EXPECT_EQ(a.stream(), 3u);
  for (int i = 0; i < 1000; ++i) {
    ASSERT_EQ(a.Normal(), b.Normal());
    ASSERT_EQ(a.Uniform(), b.Uniform());
    ASSERT_EQ(a.UnitVector(), b.UnitVector());
  }
}

TEST_F(RandomSourceTest, DifferentStreamsAndSeedsDiffer) {
  RandomSource stream0(99, 0), stream1(99, 1), other_seed(100, 0);
  int equal_streams = 0, equal_seeds = 0;
  for (int i = 0; i < 1000; ++i) {
    const double x0 = stream0.Uniform(), x1 = stream1.Uniform(), y = other_seed.Uniform();
    equal_streams += (x0 == x1);
    equal_seeds += (x0 == y);
  }
  EXPECT_EQ(equal_streams, 0);
  EXPECT_EQ(equal_seeds, 0);
}

TEST_F(RandomSourceTest, DefaultStreamIsZero) {
  RandomSource implicit(5), explicit_zero(5, 0);
  EXPECT_EQ(implicit.Normal(), explicit_zero.Normal());
}

TEST_F(RandomSourceTest, NormalHasZeroMeanUnitVarianceAndGaussianKurtosis) {
  double sum = 0, sum2 = 0, sum4 = 0;
  for (int i = 0; i < kSamples; ++i) {
    const double x = random_.Normal();
    sum += x;
    sum2 += x * x;
    sum4 += x * x * x * x;
  }
  const double n = kSamples;
  // SE: mean 1/√n = 1e-3; E[x²] √2/√n = 1.4e-3; E[x⁴] √96/√n ≈ 9.8e-3.
  EXPECT_NEAR(sum / n, 0.0, 5e-3);
  EXPECT_NEAR(sum2 / n, 1.0, 7e-3);
  EXPECT_NEAR(sum4 / n, 3.0, 5e-2);
}

TEST_F(RandomSourceTest, UniformIsInTheUnitIntervalWithTheRightMoments) {
  double sum = 0, sum2 = 0, minimum = 1, maximum = 0;
  for (int i = 0; i < kSamples; ++i) {
    const double x = random_.Uniform();
    ASSERT_GE(x, 0.0);
    ASSERT_LT(x, 1.0);
    sum += x;
    sum2 += x * x;
    minimum = std::min(minimum, x);
    maximum = std::max(maximum, x);
  }
  const double n = kSamples;
  // SE: mean √(1/12)/√n ≈ 2.9e-4; E[x²] √(4/45)/√n ≈ 3e-4.
  EXPECT_NEAR(sum / n, 0.5, 2e-3);
  EXPECT_NEAR(sum2 / n, 1.0 / 3.0, 2e-3);
  EXPECT_LT(minimum, 1e-4);
  EXPECT_GT(maximum, 1.0 - 1e-4);
}

TEST_F(RandomSourceTest, UnitVectorIsUniformOnTheSphere) {
  Vector3 sum = Vector3::Zero(), sum2 = Vector3::Zero();
  int z_in_band = 0;
  for (int i = 0; i < kSamples; ++i) {
    const Vector3 v = random_.UnitVector();
    ASSERT_NEAR(v.norm(), 1.0, 1e-15);
    sum += v;
    sum2 += v.cwiseAbs2();
    z_in_band += (v.z() > 0.2 && v.z() <= 0.7);
  }
  const double n = kSamples;
  // Each component is uniform on [−1, 1] (Archimedes): mean 0 (SE 5.8e-4), E[x²] = 1/3
  // (SE √(4/45)/√n ≈ 3e-4), P(0.2 < z ≤ 0.7) = 0.25 (SE 4.3e-4).
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(sum[axis] / n, 0.0, 3e-3) << "axis " << axis;
    EXPECT_NEAR(sum2[axis] / n, 1.0 / 3.0, 2e-3) << "axis " << axis;
  }
  EXPECT_NEAR(z_in_band / n, 0.25, 2.5e-3);
}

// The engine is MT19937-64 as boost and the standard library have it: the same outputs for the
// same seed, one at a time and through Fill (across several twists, in odd-sized pieces).
TEST(Mt19937_64Test, OutputsEqualBoostsAndTheStandardLibrarysEngines) {
  const uint64_t seeds[] = {0, 1, 5489, DeriveEngineSeed(3, 1), ~uint64_t{0}};
  for (uint64_t seed : seeds) {
    Mt19937_64 engine(seed), filled(seed);
    boost::random::mt19937_64 boost_engine(seed);
    std::mt19937_64 std_engine(seed);
    std::vector<uint64_t> block(1000);
    int in_block = 0, piece = 0;
    for (int i = 0; i < 5000; ++i) {
      const uint64_t expected = boost_engine();
      ASSERT_EQ(std_engine(), expected) << "seed " << seed << ", output " << i;
      ASSERT_EQ(engine(), expected) << "seed " << seed << ", output " << i;
      if (in_block == piece) {
        piece = piece % 397 + 1;  // 1, 2, …: pieces that straddle the 312-output twists
        filled.Fill(block.data(), piece);
        in_block = 0;
      }
      ASSERT_EQ(block[static_cast<size_t>(in_block++)], expected)
          << "seed " << seed << ", output " << i << " through Fill";
    }
  }
  // The reference value: the 10000th output of the default-seeded (5489) engine (C++11
  // [rand.predef]).
  Mt19937_64 reference(5489);
  uint64_t value = 0;
  for (int i = 0; i < 10000; ++i) value = reference();
  EXPECT_EQ(value, 9981545732273789042ULL);
}

// NormalBlock is Normal() repeated, bit for bit, for blocks of every size around its chunk (128
// outputs), including draws whose ziggurat first try fails (~1 %: the wedges and the tail, each
// consuming several outputs, some across a chunk's end), and leaves the engine where the calls
// would: the draws after it agree too.
TEST(RandomSourceBlockTest, NormalBlockEqualsSuccessiveNormalDrawsBitForBit) {
  const std::vector<int> sizes = {0, 1, 2, 63, 64, 127, 128, 129, 255, 256, 257, 1000, 100000};
  // Beyond the base strip's edge x₁ only the ziggurat's tail, after a failed first try, draws.
  const double tail_start = boost::random::detail::normal_table<double>::table_x[1];
  int64_t tail_draws = 0;
  for (uint64_t seed : {1ULL, 2ULL, 77ULL, 0xFFFFFFFFFFFFFFFFULL}) {
    RandomSource one_by_one(seed, 1), blocks(seed, 1);
    for (int size : sizes) {
      std::vector<double> expected(static_cast<size_t>(size)), got(static_cast<size_t>(size), -9.0);
      for (double& x : expected) x = one_by_one.Normal();
      blocks.NormalBlock(got.data(), size);
      for (int i = 0; i < size; ++i) {
        ASSERT_EQ(std::bit_cast<uint64_t>(got[static_cast<size_t>(i)]),
                  std::bit_cast<uint64_t>(expected[static_cast<size_t>(i)]))
            << "seed " << seed << ", block of " << size << ", draw " << i;
        tail_draws += std::abs(expected[static_cast<size_t>(i)]) > tail_start;
      }
      ASSERT_EQ(std::bit_cast<uint64_t>(blocks.Normal()), std::bit_cast<uint64_t>(one_by_one.Normal()))
          << "the draw after a block of " << size;
      ASSERT_EQ(blocks.Uniform(), one_by_one.Uniform());
    }
  }
  // The comparison covered the tail (P(|x| > 3.4426) ≈ 5.8e-4: ~236 of 4 × 102 k draws).
  EXPECT_GT(tail_draws, 50);
}

}  // namespace
}  // namespace dpc
