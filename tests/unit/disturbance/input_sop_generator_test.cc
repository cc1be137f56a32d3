#include "dpc/disturbance/input_sop_generator.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <functional>
#include <string>
#include <stdexcept>
#include <utility>
#include <vector>

#include "dpc/disturbance/constant_rotation_disturbance.h"
#include "dpc/disturbance/paper_scrambler.h"
#include "dpc/disturbance/random_walk_disturbance.h"

namespace dpc {
namespace {

/// Records the times and the order of its calls; does not change the SOP.
class RecordingDisturbance final : public Disturbance {
 public:
  RecordingDisturbance(int id, std::vector<std::pair<int, double>>* log) : id_(id), log_(log) {}
  void Advance(double t_s, StokesVector* sop, RandomSource& random) override {
    (void)sop;
    (void)random;
    log_->emplace_back(id_, t_s);
  }
  std::string Describe() const override { return "recording"; }

 private:
  int id_;
  std::vector<std::pair<int, double>>* log_;
};

class InputSopGeneratorTest : public ::testing::Test {
 protected:
  static constexpr double kSampleRateHz = 50e6;
  static constexpr uint64_t kSeed = 42;

  static std::vector<std::unique_ptr<Disturbance>> Quarter(const Vector3& first,
                                                           const Vector3& second) {
    // Quarter turns per sample at fs = 1 Hz.
    std::vector<std::unique_ptr<Disturbance>> disturbances;
    disturbances.push_back(std::make_unique<ConstantRotationDisturbance>(M_PI / 2, first, 1.0));
    disturbances.push_back(std::make_unique<ConstantRotationDisturbance>(M_PI / 2, second, 1.0));
    return disturbances;
  }

  static InputConfig PaperInput() {
    InputConfig input;
    input.disturbances.push_back(DisturbanceConfig{});  // the paper scrambler
    DisturbanceConfig walk;
    walk.kind = DisturbanceConfig::Kind::kRandomWalk;
    walk.diffusion_rad_per_sqrt_s = 10.0;
    input.disturbances.push_back(walk);
    return input;
  }
};

TEST_F(InputSopGeneratorTest, FirstNextReturnsTheInitialSop) {
  InputSopGenerator generator = MakeInputSopGenerator(PaperInput(), kSeed, kSampleRateHz);
  EXPECT_EQ(generator.sample_index(), -1);
  EXPECT_EQ(generator.Next(), StokesVector::UnitX());
  EXPECT_EQ(generator.sample_index(), 0);
  EXPECT_NE(generator.Next(), StokesVector::UnitX());
  EXPECT_EQ(generator.sample_index(), 1);
}

TEST_F(InputSopGeneratorTest, InitialSopIsNormalized) {
  InputSopGenerator generator(StokesVector(0.0, 0.6, 0.8 + 1e-9), {}, kSeed, kSampleRateHz);
  EXPECT_NEAR(generator.Next().norm(), 1.0, 1e-15);
}

TEST_F(InputSopGeneratorTest, SampleKAppliesTheDisturbancesInOrderAtTheStartOfItsInterval) {
  std::vector<std::pair<int, double>> log;
  std::vector<std::unique_ptr<Disturbance>> disturbances;
  disturbances.push_back(std::make_unique<RecordingDisturbance>(1, &log));
  disturbances.push_back(std::make_unique<RecordingDisturbance>(2, &log));
  InputSopGenerator generator(StokesVector::UnitX(), std::move(disturbances), kSeed,
                              kSampleRateHz);
  generator.Next();  // sample 0: nothing applied
  EXPECT_TRUE(log.empty());
  generator.Next();  // sample 1: the interval [0, dt)
  generator.Next();  // sample 2: [dt, 2·dt)
  const double dt = 1.0 / kSampleRateHz;
  const std::vector<std::pair<int, double>> expected = {{1, 0.0}, {2, 0.0}, {1, dt}, {2, dt}};
  EXPECT_EQ(log, expected);
}

TEST_F(InputSopGeneratorTest, CompositionOrderIsTheListOrder) {
  // From S2: R1(π/2) takes S2 to S3, which R3 keeps; R3(π/2) takes S2 to −S1, which R1 keeps.
  InputSopGenerator first_s1(StokesVector::UnitY(), Quarter(Vector3::UnitX(), Vector3::UnitZ()),
                             kSeed, 1.0);
  first_s1.Next();
  EXPECT_LT((first_s1.Next() - StokesVector::UnitZ()).norm(), 1e-15);
  InputSopGenerator first_s3(StokesVector::UnitY(), Quarter(Vector3::UnitZ(), Vector3::UnitX()),
                             kSeed, 1.0);
  first_s3.Next();
  EXPECT_LT((first_s3.Next() + StokesVector::UnitX()).norm(), 1e-15);
}

TEST_F(InputSopGeneratorTest, UsesStreamOneOfTheSeed) {
  // The same random walk run by hand on RandomSource(seed, 1) gives the same SOPs.
  std::vector<std::unique_ptr<Disturbance>> disturbances;
  disturbances.push_back(std::make_unique<RandomWalkDisturbance>(100.0, kSampleRateHz));
  InputSopGenerator generator(StokesVector::UnitZ(), std::move(disturbances), kSeed,
                              kSampleRateHz);
  RandomWalkDisturbance walk(100.0, kSampleRateHz);
  RandomSource random(kSeed, 1);
  StokesVector sop = StokesVector::UnitZ();
  EXPECT_EQ(generator.Next(), sop);
  for (int k = 1; k < 1000; ++k) {
    walk.Advance((k - 1) / kSampleRateHz, &sop, random);
    RenormalizeNearUnit(&sop);
    ASSERT_EQ(generator.Next(), sop) << "sample " << k;
  }
}

TEST_F(InputSopGeneratorTest, SameSeedSameSopsOtherSeedOtherSops) {
  InputSopGenerator a = MakeInputSopGenerator(PaperInput(), kSeed, kSampleRateHz);
  InputSopGenerator b = MakeInputSopGenerator(PaperInput(), kSeed, kSampleRateHz);
  InputSopGenerator c = MakeInputSopGenerator(PaperInput(), kSeed + 1, kSampleRateHz);
  int equal_to_other_seed = 0;
  for (int k = 0; k < 10000; ++k) {
    const StokesVector sop_a = a.Next();
    ASSERT_EQ(sop_a, b.Next()) << "sample " << k;
    equal_to_other_seed += (sop_a == c.Next());
  }
  EXPECT_EQ(equal_to_other_seed, 1);  // sample 0 only
}

TEST_F(InputSopGeneratorTest, StaysUnitOverAMillionSamples) {
  InputSopGenerator generator = MakeInputSopGenerator(PaperInput(), kSeed, kSampleRateHz);
  double worst = 0;
  for (int k = 0; k < 1000000; ++k) worst = std::max(worst, std::abs(generator.Next().norm() - 1.0));
  EXPECT_LT(worst, 1e-15);
}

TEST_F(InputSopGeneratorTest, WithoutDisturbancesTheSopHoldsStill) {
  InputSopGenerator generator(StokesVector(0.0, 0.6, 0.8), {}, kSeed, kSampleRateHz);
  const StokesVector first = generator.Next();
  for (int k = 0; k < 100; ++k) EXPECT_LT((generator.Next() - first).norm(), 1e-15);
}

TEST_F(InputSopGeneratorTest, DescribeListsTheDisturbances) {
  const std::string text =
      MakeInputSopGenerator(PaperInput(), kSeed, kSampleRateHz).Describe();
  EXPECT_NE(text.find("initial [1, 0, 0]"), std::string::npos);
  EXPECT_NE(text.find("paper scrambler"), std::string::npos);
  EXPECT_NE(text.find("random walk"), std::string::npos);
}

TEST_F(InputSopGeneratorTest, RejectsANonUnitInitialSop) {
  EXPECT_THROW(InputSopGenerator(StokesVector(0.0, 0.0, 0.5), {}, kSeed, kSampleRateHz),
               std::invalid_argument);
}

TEST_F(InputSopGeneratorTest, RejectsANullDisturbance) {
  std::vector<std::unique_ptr<Disturbance>> disturbances;
  disturbances.push_back(nullptr);
  EXPECT_THROW(InputSopGenerator(StokesVector::UnitX(), std::move(disturbances), kSeed,
                                 kSampleRateHz),
               std::invalid_argument);
}

TEST_F(InputSopGeneratorTest, RejectsABadSampleRate) {
  EXPECT_THROW(InputSopGenerator(StokesVector::UnitX(), {}, kSeed, -1.0), std::invalid_argument);
}

TEST_F(InputSopGeneratorTest, ABadDisturbanceIsNamedByItsIndex) {
  InputConfig input = PaperInput();
  input.disturbances[1].diffusion_rad_per_sqrt_s = -1.0;
  try {
    MakeInputSopGenerator(input, kSeed, kSampleRateHz);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("input.disturbances[1]"), std::string::npos)
        << error.what();
  }
}

// BeginBlock / Step / EndBlock against Next(), bit for bit, over blocks of uneven sizes (an empty
// one, one of a single sample, full ones), from the first sample on.
void ExpectBlocksEqualNext(const std::function<std::vector<std::unique_ptr<Disturbance>>()>& make,
                           const std::string& what) {
  SCOPED_TRACE(what);
  const StokesVector initial = StokesVector(1, 2, 2).normalized();
  InputSopGenerator one_by_one(initial, make(), 7, 50e6);
  InputSopGenerator blocked(initial, make(), 7, 50e6);
  const int sizes[] = {1, 0, 64, 5, 64, 33, 1, 64, 64, 17};
  int64_t sample = 0;
  for (int size : sizes) {
    InputSopGenerator::BlockCursor cursor = blocked.BeginBlock(size);
    for (int i = 0; i < size; ++i, ++sample) {
      const StokesVector expected = one_by_one.Next();
      const StokesVector got = blocked.Step(i, &cursor);
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(std::bit_cast<uint64_t>(got[c]), std::bit_cast<uint64_t>(expected[c]))
            << "sample " << sample << " component " << c;
      }
    }
    blocked.EndBlock(cursor);
    EXPECT_EQ(blocked.sample_index(), one_by_one.sample_index());
  }
  // Next() goes on from the blocks' last SOP.
  for (int k = 0; k < 10; ++k) {
    const StokesVector expected = one_by_one.Next();
    EXPECT_EQ(blocked.Next(), expected);
  }
}

TEST_F(InputSopGeneratorTest, BlocksGiveWhatNextGivesBitForBit) {
  const auto scrambler = [](double rate_rad_per_s, double kick_ratio, Vector3 axis, Vector3 kick) {
    return [=] {
      std::vector<std::unique_ptr<Disturbance>> d;
      d.push_back(std::make_unique<PaperScrambler>(rate_rad_per_s, kick_ratio, axis, kick, 50e6));
      return d;
    };
  };
  ExpectBlocksEqualNext(scrambler(1e5, 1.0, Vector3::UnitZ(), Vector3::UnitY()),
                        "the paper's scrambler");
  ExpectBlocksEqualNext(scrambler(1e5, 0.0, Vector3::UnitZ(), Vector3::UnitY()),
                        "without kicks");
  ExpectBlocksEqualNext(scrambler(2e5, 0.5, Vector3::UnitX(), Vector3::UnitZ()),
                        "other elemental axes");
  // Kicks of σ = 0.02 rad: beyond the small-angle series now and then (the library's sin/cos).
  ExpectBlocksEqualNext(scrambler(1e5, 10.0, Vector3::UnitZ(), Vector3::UnitY()),
                        "large kicks");
  ExpectBlocksEqualNext(scrambler(1e5, 1.0, Vector3(1, 1, 0), Vector3::UnitY()),
                        "a general rotation axis");
  ExpectBlocksEqualNext(
      [] {
        std::vector<std::unique_ptr<Disturbance>> d;
        d.push_back(std::make_unique<RandomWalkDisturbance>(1e3, 50e6));
        d.push_back(std::make_unique<ConstantRotationDisturbance>(1e5, Vector3::UnitZ(), 50e6));
        return d;
      },
      "other disturbances");
}

TEST_F(InputSopGeneratorTest, ABlockLargerThanTheMostIsRefused) {
  InputSopGenerator generator(StokesVector::UnitX(), {}, kSeed, kSampleRateHz);
  EXPECT_THROW(generator.BeginBlock(InputSopGenerator::kMaxBlock + 1), std::invalid_argument);
  EXPECT_THROW(generator.BeginBlock(-1), std::invalid_argument);
  EXPECT_EQ(generator.sample_index(), -1);
}

}  // namespace
}  // namespace dpc
