#include "dpc/disturbance/recorded_input_disturbance.h"

#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>

#include "dpc/disturbance/input_sop_generator.h"

namespace dpc {
namespace {

std::shared_ptr<const RecordedInput> ThreeSops() {
  auto recorded = std::make_shared<RecordedInput>();
  recorded->source = "session.mcap";
  recorded->sops = {StokesVector::UnitX(), StokesVector::UnitY(), StokesVector::UnitZ()};
  return recorded;
}

TEST(RecordedInputDisturbanceTest, TheGeneratorReturnsTheRecordedSopsInOrderThenHoldsTheLast) {
  InputConfig input;
  input.recorded = ThreeSops();
  input.initial_sop = StokesVector(0.0, -1.0, 0.0);  // not used beside a recording
  InputSopGenerator generator = MakeInputSopGenerator(input, 7, 1e3);
  EXPECT_EQ(generator.Next(), StokesVector::UnitX());
  EXPECT_EQ(generator.Next(), StokesVector::UnitY());
  EXPECT_EQ(generator.Next(), StokesVector::UnitZ());
  EXPECT_EQ(generator.Next(), StokesVector::UnitZ());
  EXPECT_EQ(generator.Next(), StokesVector::UnitZ());
  EXPECT_EQ(generator.sample_index(), 4);
  EXPECT_NE(generator.Describe().find("recorded input: 3 samples of session.mcap"), std::string::npos)
      << generator.Describe();
}

TEST(RecordedInputDisturbanceTest, ASetSopIsKeptWhateverCameBefore) {
  RecordedInputDisturbance recorded(ThreeSops());
  RandomSource random(1, 1);
  StokesVector sop(0.0, 0.0, -1.0);
  recorded.Advance(0.0, &sop, random);
  EXPECT_EQ(sop, StokesVector::UnitY());
  sop = StokesVector::UnitX();
  recorded.Advance(1e-3, &sop, random);
  EXPECT_EQ(sop, StokesVector::UnitZ());
}

TEST(RecordedInputDisturbanceTest, AnEmptyRecordingOrDisturbancesBesideItAreRefused) {
  EXPECT_THROW(RecordedInputDisturbance(nullptr), std::invalid_argument);
  EXPECT_THROW(RecordedInputDisturbance(std::make_shared<RecordedInput>()), std::invalid_argument);
  InputConfig input;
  input.recorded = ThreeSops();
  input.disturbances.push_back(DisturbanceConfig{});
  EXPECT_THROW(MakeInputSopGenerator(input, 7, 1e3), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
