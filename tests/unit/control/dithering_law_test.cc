#include "dpc/control/dithering_law.h"

#include <gtest/gtest.h>

#include <deque>

#include "support/control_fixture.h"

namespace dpc {
namespace {

using testing::ControlFixture;

const Target kPaperTarget = Target::Point(StokesVector(0, 0.6, 0.8));

class DitheringLawTest : public ::testing::Test, public ControlFixture {
 protected:
  DitheringLawTest() : ControlFixture("3131") {}

  // A loop with a command delay of `delay` samples; the law sees the measured output.
  ControlVector Run(DitheringLaw& law, ControlVector phi, const StokesVector& s_in, int delay,
                    int samples) {
    std::deque<ControlVector> in_flight(delay, phi);
    law.Activate(phi);
    ControlVector command = phi;
    for (int k = 0; k < samples; ++k) {
      const ControlVector applied = in_flight.front();
      in_flight.pop_front();
      const StokesVector measured = chain().Output(applied, s_in);
      ControlVector delta;
      EXPECT_EQ(law.ComputeUpdate(Build(command, s_in, kPaperTarget, LoopMode::kModel, measured),
                                  &delta),
                ControlStatus::kOk);
      command += delta;
      in_flight.push_back(command);
    }
    return command;
  }
};

TEST_F(DitheringLawTest, ConvergesOnAStaticInputWithoutAModel) {
  DitherSettings settings;
  settings.amplitude = 0.01;
  settings.settle_samples = 3;
  settings.reset_threshold = 5.0;
  DitheringLaw law(0.2, settings);
  ControlVector phi(4);
  phi << 0.1, 0.2, -0.1, 0.3;
  const StokesVector s_in = StokesVector(0.6, -0.3, 0.74).normalized();
  const double before = kPaperTarget.DistanceRad(chain().Output(phi, s_in));
  const ControlVector after = Run(law, phi, s_in, 3, 20000);
  EXPECT_GT(before, 0.5);
  EXPECT_LT(kPaperTarget.DistanceRad(chain().Output(after, s_in)), 0.05);
  EXPECT_EQ(law.diagnostics().resets, 0);
}

TEST_F(DitheringLawTest, ResetsAControlByAFullTurnWithoutChangingTheSteadyOutput) {
  DitherSettings settings;
  settings.amplitude = 1e-6;
  settings.settle_samples = 1;
  settings.reset_threshold = 1.0;
  settings.reset_samples = 10;
  DitheringLaw law(1e-6, settings);
  ControlVector phi(4);
  phi << 1.5, 0.2, -0.1, 0.3;
  const StokesVector s_in = StokesVector(0.6, -0.3, 0.74).normalized();
  const StokesVector before = chain().Output(phi, s_in);
  const ControlVector after = Run(law, phi, s_in, 1, 8 + 10 + 4);
  EXPECT_EQ(law.diagnostics().resets, 1);
  EXPECT_NEAR(after[0], -0.5, 1e-4);  // θ = π·1.5 wound back by 2π
  EXPECT_LT((chain().Output(after, s_in) - before).norm(), 1e-4);
}

TEST_F(DitheringLawTest, RejectsBadSettings) {
  DitherSettings s;
  s.amplitude = 0.0;
  EXPECT_THROW(DitheringLaw(0.1, s), std::invalid_argument);
  s = DitherSettings{};
  s.settle_samples = 0;
  EXPECT_THROW(DitheringLaw(0.1, s), std::invalid_argument);
  s = DitherSettings{};
  s.reset_samples = 0;
  EXPECT_THROW(DitheringLaw(0.1, s), std::invalid_argument);
  EXPECT_THROW(DitheringLaw(-0.1, DitherSettings{}), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
