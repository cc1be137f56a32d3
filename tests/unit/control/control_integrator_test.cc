#include "dpc/control/control_integrator.h"

#include <gtest/gtest.h>

namespace dpc {
namespace {

class ControlIntegratorTest : public ::testing::Test {
 protected:
  ControlIntegratorTest() : chain_(MakeChain()) {}
  static WaveplateChain MakeChain() {
    std::vector<WaveplateStage> stages;
    stages.push_back(WaveplateStage::FixedAxis(Vector3::UnitX(), ControlMap::Linear(),
                                               ControlRange{-1.0, 1.0}));
    stages.push_back(WaveplateStage::FixedAxis(Vector3::UnitZ()));
    return WaveplateChain(std::move(stages));
  }
  static ControlVector Vec(double a, double b) {
    ControlVector v(2);
    v << a, b;
    return v;
  }
  WaveplateChain chain_;
};

TEST_F(ControlIntegratorTest, AddsUsableUpdates) {
  ControlIntegrator integrator(chain_, Vec(0.1, 0.2));
  EXPECT_EQ(integrator.Apply(ControlStatus::kOk, Vec(0.3, -0.5)),
            ControlIntegrator::Outcome::kApplied);
  EXPECT_NEAR(integrator.phi()[0], 0.4, 1e-15);
  EXPECT_NEAR(integrator.phi()[1], -0.3, 1e-15);
  EXPECT_EQ(integrator.Apply(ControlStatus::kRankDeficient, Vec(0.1, 0.0)),
            ControlIntegrator::Outcome::kApplied);
}

TEST_F(ControlIntegratorTest, NeverAppliesFailedNonFiniteOrMisSizedUpdates) {
  ControlIntegrator integrator(chain_, Vec(0.1, 0.2));
  EXPECT_EQ(integrator.Apply(ControlStatus::kSingular, Vec(0.3, 0.3)),
            ControlIntegrator::Outcome::kRejected);
  EXPECT_EQ(integrator.Apply(ControlStatus::kOk, Vec(NAN, 0.3)),
            ControlIntegrator::Outcome::kRejected);
  EXPECT_EQ(integrator.Apply(ControlStatus::kOk, Vec(0.1, INFINITY)),
            ControlIntegrator::Outcome::kRejected);
  ControlVector three(3);
  three.setZero();
  EXPECT_EQ(integrator.Apply(ControlStatus::kOk, three), ControlIntegrator::Outcome::kRejected);
  EXPECT_EQ(integrator.rejected(), 4);
  EXPECT_EQ(integrator.phi(), Vec(0.1, 0.2));
}

TEST_F(ControlIntegratorTest, ClampsIntoRangesWithoutWindUp) {
  ControlIntegrator integrator(chain_, Vec(0.9, 0.0));
  EXPECT_EQ(integrator.Apply(ControlStatus::kOk, Vec(0.5, 5.0)),
            ControlIntegrator::Outcome::kClamped);
  EXPECT_EQ(integrator.phi()[0], 1.0);
  EXPECT_EQ(integrator.phi()[1], 5.0);
  // No wind-up: one step back leaves the limit at once.
  integrator.Apply(ControlStatus::kOk, Vec(-0.1, 0.0));
  EXPECT_NEAR(integrator.phi()[0], 0.9, 1e-15);
  EXPECT_EQ(integrator.clamped(), 1);
}

TEST_F(ControlIntegratorTest, RejectsBadInitialValues) {
  EXPECT_THROW(ControlIntegrator(chain_, ControlVector::Zero(3)), std::invalid_argument);
  EXPECT_THROW(ControlIntegrator(chain_, Vec(NAN, 0.0)), std::invalid_argument);
  ControlIntegrator clamped(chain_, Vec(3.0, 0.0));
  EXPECT_EQ(clamped.phi()[0], 1.0);
}

}  // namespace
}  // namespace dpc
