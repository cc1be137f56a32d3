#include "dpc/optics/waveplate_chain.h"

#include <Eigen/SVD>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "dpc/optics/numeric_jacobian.h"
#include "dpc/optics/rotation.h"

namespace dpc {
namespace {

class WaveplateChainTest : public ::testing::Test {
 protected:
  std::mt19937_64 rng_{2024};
  std::normal_distribution<double> normal_;

  StokesVector RandomSop() {
    return StokesVector(normal_(rng_), normal_(rng_), normal_(rng_)).normalized();
  }
  ControlVector RandomPhi(int n, double scale = 1.0) {
    ControlVector phi(n);
    for (int i = 0; i < n; ++i) phi[i] = scale * normal_(rng_);
    return phi;
  }

  // Closed form vs central differences; every column ⊥ S_out; rank ≤ 2.
  void ExpectJacobianProperties(const WaveplateChain& chain, double fd_tolerance = 1e-8) {
    for (int trial = 0; trial < 50; ++trial) {
      const ControlVector phi = RandomPhi(chain.control_count());
      const StokesVector s_in = RandomSop();
      ChainPose pose;
      chain.ComputePose(phi, &pose);
      ChainKinematics k;
      chain.Evaluate(pose, s_in, &k);
      const Matrix3X numeric = NumericJacobian(chain, phi, s_in);
      EXPECT_LT((k.jacobian - numeric).norm(), fd_tolerance * std::max(1.0, numeric.norm()))
          << chain.Describe() << "\nclosed form\n" << k.jacobian << "\nnumeric\n" << numeric;
      EXPECT_LT((k.s_out - chain.Output(pose, s_in)).norm(), 1e-14);
      EXPECT_LT((k.mueller - chain.MuellerMatrix(pose)).norm(), 1e-13);
      // Input frame: MᵀJ_c = Ω′_c × S_in.
      for (int c = 0; c < chain.control_count(); ++c) {
        const Vector3 pulled_back = k.mueller.transpose() * k.jacobian.col(c);
        EXPECT_LT((pulled_back - Vector3(k.input_generators.col(c)).cross(s_in)).norm(), 1e-12);
      }
      for (int c = 0; c < chain.control_count(); ++c) {
        EXPECT_NEAR(k.jacobian.col(c).dot(k.s_out), 0.0, 1e-13);
      }
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(Eigen::MatrixXd(k.jacobian));
      const auto& sv = svd.singularValues();
      if (sv.size() == 3) {
        EXPECT_LT(sv[2], 1e-12 * std::max(1.0, sv[0])) << chain.Describe();
      }
    }
  }
};

TEST_F(WaveplateChainTest, PaperThreeStageOutputIsR1R3R1) {
  const WaveplateChain chain = WaveplateChain::FromAxes("131");
  ASSERT_EQ(chain.stage_count(), 3);
  ASSERT_EQ(chain.control_count(), 3);
  EXPECT_EQ(chain.Describe(), "R1 R3 R1");
  const ControlVector phi = RandomPhi(3);
  const StokesVector s_in = RandomSop();
  const StokesVector expected = R1(M_PI * phi[2]) * R3(M_PI * phi[1]) * R1(M_PI * phi[0]) * s_in;
  EXPECT_LT((chain.Output(phi, s_in) - expected).norm(), 1e-14);
}

TEST_F(WaveplateChainTest, AxesStringListsStagesInLightOrder) {
  // "3131": the light meets R3 first, so M = R1 R3 R1 R3 as the paper writes it.
  const WaveplateChain chain = WaveplateChain::FromAxes("3131");
  const ControlVector phi = RandomPhi(4);
  ChainPose pose;
  chain.ComputePose(phi, &pose);
  const Matrix3 expected =
      R1(M_PI * phi[3]) * R3(M_PI * phi[2]) * R1(M_PI * phi[1]) * R3(M_PI * phi[0]);
  EXPECT_LT((chain.MuellerMatrix(pose) - expected).norm(), 1e-14);
  EXPECT_EQ(chain.Describe(), "R3 R1 R3 R1");
  EXPECT_EQ(chain.PaperNotation(), "R1R3R1R3");
  EXPECT_EQ(WaveplateChain::FromAxes("131").PaperNotation(), "R1R3R1");
  EXPECT_EQ(WaveplateChain::FromAxes("123").PaperNotation(), "R3R2R1");
}

TEST_F(WaveplateChainTest, PaperJacobianFormForThreeStages) {
  // Paper eq. 7 with θ = kφ: J = k [M3M2(r1×S'), M3(r2×S''), r3×S'''].
  const double k = M_PI;
  const WaveplateChain chain = WaveplateChain::FromAxes("131", k);
  const ControlVector phi = RandomPhi(3);
  const StokesVector s_in = RandomSop();
  const Matrix3 m1 = R1(k * phi[0]), m2 = R3(k * phi[1]), m3 = R1(k * phi[2]);
  const Vector3 s1 = m1 * s_in, s2 = m2 * s1, s3 = m3 * s2;
  Matrix3 expected;
  expected.col(0) = k * (m3 * m2 * Vector3::UnitX().cross(s1));
  expected.col(1) = k * (m3 * Vector3::UnitZ().cross(s2));
  expected.col(2) = k * Vector3::UnitX().cross(s3);
  EXPECT_LT((chain.Jacobian(phi, s_in) - expected).norm(), 1e-13);
}

TEST_F(WaveplateChainTest, JacobianMatchesFiniteDifferencesForElementalChains) {
  for (const char* axes : {"1", "13", "131", "3131", "123", "21312", "1313131313131313"}) {
    ExpectJacobianProperties(WaveplateChain::FromAxes(axes));
  }
}

TEST_F(WaveplateChainTest, JacobianMatchesFiniteDifferencesForGeneralAxesAndMaps) {
  std::vector<WaveplateStage> stages;
  stages.push_back(WaveplateStage::FixedAxis(Vector3(1, 1, 0), ControlMap::Linear(2.0, 0.3)));
  stages.push_back(WaveplateStage::FixedAxis(-Vector3::UnitZ(),
                                             ControlMap::Polynomial({0.2, 2.5, -0.4, 0.3})));
  stages.push_back(WaveplateStage::FixedAxis(Vector3(0.2, -0.5, 0.9)));
  stages.push_back(WaveplateStage::FixedAxis(Vector3::UnitY(), ControlMap::Linear(-1.5)));
  ExpectJacobianProperties(WaveplateChain(std::move(stages)));
}

TEST_F(WaveplateChainTest, JacobianMatchesFiniteDifferencesForAdjustableAxisStages) {
  std::vector<WaveplateStage> stages;
  stages.push_back(WaveplateStage::AdjustableAxis(StageAngle::Controlled(ControlMap::Linear()),
                                                  StageAngle::Controlled(ControlMap::Linear(2.0))));
  stages.push_back(WaveplateStage::AdjustableAxis(StageAngle::Fixed(M_PI / 2),
                                                  StageAngle::Controlled(ControlMap::Linear())));
  stages.push_back(WaveplateStage::AdjustableAxis(
      StageAngle::Controlled(ControlMap::Polynomial({0.0, 3.0, 0.5})), StageAngle::Fixed(0.4)));
  const WaveplateChain chain(std::move(stages));
  EXPECT_EQ(chain.control_count(), 4);
  EXPECT_EQ(chain.controls()[0].name, "phi_1.retardance");
  EXPECT_EQ(chain.controls()[1].name, "phi_1.orientation");
  EXPECT_EQ(chain.controls()[2].name, "phi_2.orientation");
  EXPECT_EQ(chain.controls()[3].name, "phi_3.retardance");
  ExpectJacobianProperties(chain);
}

TEST_F(WaveplateChainTest, TableMapsUseTheirNumericDerivative) {
  // A measured table close to θ = πφ with a slight nonlinearity; knots every 0.05.
  std::vector<double> control, angle;
  for (int i = -80; i <= 80; ++i) {
    const double x = 0.05 * i;
    control.push_back(x);
    angle.push_back(M_PI * x + 0.1 * std::sin(2 * x));
  }
  std::vector<WaveplateStage> stages;
  for (const Vector3& axis : std::vector<Vector3>{Vector3::UnitX(), Vector3::UnitZ(), Vector3::UnitX()}) {
    stages.push_back(WaveplateStage::FixedAxis(axis, ControlMap::Table(control, angle)));
  }
  const WaveplateChain chain(std::move(stages));
  // Finite differences with h = 1e-6 straddle a knot only within 1e-6 of it; random φ do not.
  ExpectJacobianProperties(chain, 1e-7);
}

TEST_F(WaveplateChainTest, IncrementalPoseStaysWithinRoundOffOfTheExactOne) {
  const WaveplateChain chain = WaveplateChain::FromAxes("3131");
  ControlVector phi = RandomPhi(4);
  ChainPose incremental, exact;
  chain.ComputePose(phi, &incremental);
  double worst = 0.0;
  for (int step = 0; step < 3000; ++step) {
    for (int c = 0; c < 4; ++c) phi[c] += 1e-3 * normal_(rng_);
    if (step == 1000) phi[2] += 0.5;  // a large step: exact sines and cosines again
    chain.ComputePoseFrom(incremental, phi, &incremental);
    chain.ComputePose(phi, &exact);
    for (int e = 0; e < 4; ++e) {
      worst = std::max(worst, std::abs(incremental.cos[e] - exact.cos[e]));
      worst = std::max(worst, std::abs(incremental.sin[e] - exact.sin[e]));
      EXPECT_EQ(incremental.angle_rad[e], exact.angle_rad[e]);
    }
  }
  EXPECT_LT(worst, 1e-13);
  EXPECT_LE(incremental.incremental_steps, WaveplateChain::kMaxIncrementalSteps);
}

TEST_F(WaveplateChainTest, StageStatesEndAtTheOutput) {
  const WaveplateChain chain = WaveplateChain::FromAxes("3131");
  const ControlVector phi = RandomPhi(4);
  const StokesVector s_in = RandomSop();
  ChainPose pose;
  chain.ComputePose(phi, &pose);
  const auto states = chain.StageStates(pose, s_in);
  ASSERT_EQ(states.size(), 5u);
  EXPECT_EQ(states.front(), s_in);
  EXPECT_LT((states.back() - chain.Output(pose, s_in)).norm(), 1e-14);
  EXPECT_LT((states[1] - R3(M_PI * phi[0]) * s_in).norm(), 1e-14);
}

TEST_F(WaveplateChainTest, SingularWhenAStateMeetsItsStageAxis) {
  // Paper: J loses a column when S' coincides with the first stage's axis: S_in = S1 with an R1
  // first stage makes column 1 zero.
  const WaveplateChain chain = WaveplateChain::FromAxes("131");
  const Matrix3X j = chain.Jacobian(RandomPhi(3), Vector3::UnitX());
  EXPECT_LT(j.col(0).norm(), 1e-15);
}

TEST_F(WaveplateChainTest, RejectsBadStageCounts) {
  EXPECT_THROW(WaveplateChain(std::vector<WaveplateStage>{}), std::invalid_argument);
  EXPECT_THROW(WaveplateChain::FromAxes(std::string(17, '1')), std::invalid_argument);
  EXPECT_NO_THROW(WaveplateChain::FromAxes(std::string(16, '1')));
  EXPECT_THROW(WaveplateChain::FromAxes("1x3"), std::invalid_argument);
  EXPECT_THROW(WaveplateChain::FromAxes(""), std::invalid_argument);
}

TEST_F(WaveplateChainTest, ClampToRangesCountsClampedControls) {
  std::vector<WaveplateStage> stages;
  stages.push_back(WaveplateStage::FixedAxis(Vector3::UnitX(), ControlMap::Linear(),
                                             ControlRange{-1, 1}));
  stages.push_back(WaveplateStage::FixedAxis(Vector3::UnitZ()));
  const WaveplateChain chain(std::move(stages));
  ControlVector phi(2);
  phi << 1.5, 7.0;
  EXPECT_EQ(chain.ClampToRanges(&phi), 1);
  EXPECT_EQ(phi[0], 1.0);
  EXPECT_EQ(phi[1], 7.0);
}

}  // namespace
}  // namespace dpc
