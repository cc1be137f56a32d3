#include "dpc/control/gradient_projection_law.h"

#include "dpc/control/jacobian_laws.h"

#include <gtest/gtest.h>

#include <random>

#include "support/control_fixture.h"

namespace dpc {
namespace {

using testing::ControlFixture;
using testing::SvdPseudoInverse;

const Target kPaperTarget = Target::Point(StokesVector(0, 0.6, 0.8));

class GradientProjectionLawTest : public ::testing::Test, public ControlFixture {
 protected:
  GradientProjectionLawTest() : ControlFixture("3131") {}
};

TEST_F(GradientProjectionLawTest, MatchesThePapersEquationWithSvd) {
  // Paper eq. 10: Δφ = μ J⁺ΔS − μ_N (I − J⁺J) φ.
  GradientProjectionLaw law(0.1, 0.05);
  for (int trial = 0; trial < 30; ++trial) {
    const ControlVector phi = RandomPhi(1.5);
    ControlProblem& p = Build(phi, RandomSop(), kPaperTarget);
    ControlVector delta;
    ASSERT_TRUE(IsUsable(law.ComputeUpdate(p, &delta)));
    const Eigen::MatrixXd j = FullTaskJacobian();
    const Eigen::MatrixXd pinv = SvdPseudoInverse(j);
    const Eigen::VectorXd phi_d = Eigen::VectorXd(phi);
    const Eigen::VectorXd expected =
        0.1 * pinv * FullTaskError() -
        0.05 * (Eigen::MatrixXd::Identity(4, 4) - pinv * j) * phi_d;
    EXPECT_LT((Eigen::VectorXd(delta) - expected).norm(), 1e-10 * std::max(1.0, expected.norm()));
    EXPECT_TRUE(law.diagnostics().nullspace_active);
  }
}

TEST_F(GradientProjectionLawTest, NullSpaceTermDoesNotMoveTheOutput) {
  // With the target reached, the update is the null-space term alone: J Δφ = 0.
  GradientProjectionLaw law(0.1, 0.5);
  const ControlVector phi = RandomPhi(1.5);
  const StokesVector s_in = RandomSop();
  const Target here = Target::Point(chain().Output(phi, s_in));
  ControlProblem& p = Build(phi, s_in, here);
  ControlVector delta;
  ASSERT_TRUE(IsUsable(law.ComputeUpdate(p, &delta)));
  EXPECT_GT(delta.norm(), 1e-3);
  EXPECT_LT((p.kinematics.jacobian * delta).norm(), 1e-12);
}

TEST_F(GradientProjectionLawTest, ThresholdGatesTheNullSpaceTerm) {
  GradientProjectionLaw law(0.1, 0.5, 1.0);
  EXPECT_EQ(law.name(), "gpt");
  const StokesVector s_in = RandomSop();
  ControlVector small(4), large(4);
  small << 0.2, -0.5, 0.9, 0.1;
  large << 0.2, -1.2, 0.9, 0.1;
  ControlVector delta;
  law.ComputeUpdate(Build(small, s_in, kPaperTarget), &delta);
  EXPECT_FALSE(law.diagnostics().nullspace_active);
  PseudoInverseLaw pinv(0.1);
  ControlVector pinv_delta;
  pinv.ComputeUpdate(problem(), &pinv_delta);
  EXPECT_LT((delta - pinv_delta).norm(), 1e-15);
  law.ComputeUpdate(Build(large, s_in, kPaperTarget), &delta);
  EXPECT_TRUE(law.diagnostics().nullspace_active);
}

TEST_F(GradientProjectionLawTest, StaticLoopLocksAndMinimizesTheControlNorm) {
  // Without delay or motion, iterating φ ← φ + Δφ must reach S* and then keep reducing ‖φ‖
  // inside the fibre of controls that give S*.
  GradientProjectionLaw law(0.5, 0.2);
  const StokesVector s_in = StokesVector(0.3, -0.8, 0.52).normalized();
  ControlVector phi(4);
  phi << 1.7, -1.4, 1.1, 0.9;
  double locked_norm = -1.0;
  for (int k = 0; k < 400; ++k) {
    ControlProblem& p = Build(phi, s_in, kPaperTarget);
    ControlVector delta;
    ASSERT_TRUE(IsUsable(law.ComputeUpdate(p, &delta)));
    phi += delta;
    if (k == 100) locked_norm = phi.norm();
  }
  const StokesVector s_out = chain().Output(phi, s_in);
  EXPECT_LT(kPaperTarget.DistanceRad(s_out), 1e-9);
  EXPECT_LT(phi.norm(), locked_norm);
  // Stationary: no null-space component left.
  ControlProblem& p = Build(phi, s_in, kPaperTarget);
  TaskPseudoInverse pinv;
  pinv.Compute(p.task_jacobian);
  ControlVector residual;
  pinv.NullSpaceProjection(phi, &residual);
  EXPECT_LT(residual.norm(), 1e-6);
}

TEST_F(GradientProjectionLawTest, RejectsBadParameters) {
  EXPECT_THROW(GradientProjectionLaw(0.0, 0.1), std::invalid_argument);
  EXPECT_THROW(GradientProjectionLaw(0.1, -0.1), std::invalid_argument);
  EXPECT_THROW(GradientProjectionLaw(0.1, 0.1, -1.0), std::invalid_argument);
  EXPECT_THROW(GradientProjectionLaw(0.1, NAN), std::invalid_argument);
}

}  // namespace
}  // namespace dpc

namespace dpc {
namespace {

using testing::ControlFixture;

// R1R3R1 at φ = 0 with S_in in the s1–s3 plane is singular: the columns S1 × S_in and
// S3 × S_in are parallel (and the third equals the first). A small offset of S_in out of the
// plane makes σ_min small but non-zero.
class GradientProjectionDampingTest : public ::testing::Test, public ControlFixture {
 protected:
  GradientProjectionDampingTest() : ControlFixture("131") {}
};

TEST_F(GradientProjectionDampingTest, DampingBoundsTheStepNearAConstructedSingularity) {
  const Target target = Target::Point(StokesVector(0, 0.6, 0.8));
  const ControlVector phi = ControlVector::Zero(3);
  GradientProjectionOptions options;
  options.max_damping = 0.5;
  options.damping_threshold = 0.5;
  GradientProjectionLaw plain(0.1, 0.1), damped(0.1, 0.1, options);
  for (double offset : {1e-2, 1e-4, 1e-6}) {
    const StokesVector s_in = StokesVector(0.6, offset, 0.8).normalized();
    ControlProblem& p = Build(phi, s_in, target);
    ControlVector plain_delta, damped_delta;
    ASSERT_TRUE(IsUsable(plain.ComputeUpdate(p, &plain_delta)));
    ASSERT_TRUE(IsUsable(damped.ComputeUpdate(p, &damped_delta)));
    EXPECT_LT(plain.diagnostics().singular_values.min(), 0.1);
    // Plain: the step grows like 1/σ_min. Damped: bounded by μ|e|/ε whatever σ_min.
    EXPECT_GT(plain_delta.norm(), 0.1 * 0.5 / (10.0 * offset));
    EXPECT_LT(damped_delta.norm(), 0.1 * 2.0 / 0.5);
    EXPECT_GT(damped.damping_squared(), 0.0);
  }
}

TEST_F(GradientProjectionDampingTest, AwayFromSingularitiesDampingChangesNothing) {
  const Target target = Target::Point(StokesVector(0, 0.6, 0.8));
  GradientProjectionOptions options;
  options.max_damping = 0.5;
  options.damping_threshold = 0.2;
  GradientProjectionLaw plain(0.1, 0.1), damped(0.1, 0.1, options);
  int compared = 0;
  for (int trial = 0; trial < 50; ++trial) {
    ControlProblem& p = Build(RandomPhi(0.7), RandomSop(), target);
    ControlVector plain_delta, damped_delta;
    ASSERT_TRUE(IsUsable(plain.ComputeUpdate(p, &plain_delta)));
    ASSERT_TRUE(IsUsable(damped.ComputeUpdate(p, &damped_delta)));
    if (plain.diagnostics().singular_values.min() < 0.2) continue;
    EXPECT_LT((plain_delta - damped_delta).norm(), 1e-12);
    ++compared;
  }
  EXPECT_GT(compared, 30);
}

// Stages of the given axes (light order), each with range [−limit, limit] and θ = rad_per_unit·φ.
WaveplateChain RangedChain(const std::string& axes, double limit, double rad_per_unit = M_PI) {
  std::vector<WaveplateStage> stages;
  for (char c : axes) {
    const Vector3 axis = c == '1' ? Vector3::UnitX() : c == '2' ? Vector3::UnitY() : Vector3::UnitZ();
    stages.push_back(
        WaveplateStage::FixedAxis(axis, ControlMap::Linear(rad_per_unit), ControlRange{-limit, limit}));
  }
  return WaveplateChain(std::move(stages));
}

// A closed model loop against a rotating input, φ integrated as the simulator does.
struct RangeLoopResult {
  double largest_phi = 0.0;
  double final_error_rad = 0.0;
  int saturated_updates = 0;
};

RangeLoopResult RunRangeLoop(const WaveplateChain& chain, GradientProjectionLaw* law,
                             int updates, double rad_per_update) {
  const Target target = Target::Point(StokesVector(0, 0.6, 0.8));
  ControlProblem problem;
  problem.chain = &chain;
  problem.target = &target;
  problem.need_jacobian = false;
  ChainPose pose;
  ControlVector phi = ControlVector::Zero(chain.control_count()), delta;
  const Matrix3 turn = RotationAboutAxis(Vector3(0.2, 0.3, 1.0).normalized(), rad_per_update);
  StokesVector s_in = StokesVector(1, 0, 0);
  RangeLoopResult result;
  for (int k = 0; k < updates; ++k) {
    s_in = turn * s_in;
    chain.ComputePose(phi, &pose);
    problem.pose = &pose;
    problem.s_in = s_in;
    UpdateControlProblem(&problem);
    if (!IsUsable(law->ComputeUpdate(problem, &delta))) continue;
    phi += delta;  // no clamp: the law alone must keep φ inside
    result.saturated_updates += law->saturated_controls() > 0;
    for (int i = 0; i < phi.size(); ++i) {
      result.largest_phi = std::max(result.largest_phi, std::abs(phi[i]));
    }
  }
  chain.ComputePose(phi, &pose);
  result.final_error_rad = target.DistanceRad(chain.Output(pose, s_in));
  return result;
}

TEST(GradientProjectionRangeTest, RangeNeverExceededWhileTracking) {
  for (const std::string axes : {"3131", "131"}) {
    const WaveplateChain chain = RangedChain(axes, 1.0);
    GradientProjectionOptions options;
    options.range_aware = true;
    options.max_damping = 0.5;
    GradientProjectionLaw law(0.5, 0.2, options);
    const RangeLoopResult r = RunRangeLoop(chain, &law, 20000, 0.01);
    EXPECT_LE(r.largest_phi, 1.0) << axes;
    EXPECT_LT(r.final_error_rad, 0.1) << axes;
  }
}

TEST(GradientProjectionRangeTest, SaturatesAtTheLimitAndSolvesTheTaskWithTheOthers) {
  // A narrow range that the task needs to leave: the controls that would leave are fixed at
  // their limits and the others still reduce the error.
  const WaveplateChain chain = RangedChain("3131", 0.3);
  const Target target = Target::Point(StokesVector(0, 0.6, 0.8));
  GradientProjectionOptions options;
  options.range_aware = true;
  GradientProjectionLaw law(1.0, 0.0, options);
  ControlProblem problem;
  problem.chain = &chain;
  problem.target = &target;
  problem.need_jacobian = true;
  ChainPose pose;
  ControlVector phi(4);
  phi << 0.29, -0.1, 0.2, 0.0;
  chain.ComputePose(phi, &pose);
  problem.pose = &pose;
  problem.s_in = StokesVector(0.2, -0.9, 0.3).normalized();
  UpdateControlProblem(&problem);
  const double before = target.DistanceRad(problem.kinematics.s_out);
  ControlVector delta;
  ASSERT_TRUE(IsUsable(law.ComputeUpdate(problem, &delta)));
  EXPECT_GT(law.saturated_controls(), 0);
  const ControlVector next = phi + delta;
  for (int i = 0; i < 4; ++i) {
    EXPECT_LE(std::abs(next[i]), 0.3 + 1e-15) << i;
  }
  EXPECT_LT(target.DistanceRad(chain.Output(next, problem.s_in)), before);
}

TEST(GradientProjectionRangeTest, TheRangeCriterionDoesNotDependOnTheControlsUnit) {
  // The same device in two units: φ in units of π rad with range ±1, and in "volts" with
  // θ = (π/10)·V and range ±10 V. Every term of the law must scale with the unit (Δφ in volts =
  // 10 × Δφ in units of π rad), as the paper's ½‖φ‖² does: a criterion whose gradient is in
  // 1/unit would pull 100 times less in volts, and φ would drift to the ends of its range.
  const Target target = Target::Point(StokesVector(0, 0.6, 0.8));
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> uniform(-0.9, 0.9);
  for (const std::string axes : {"131", "3131"}) {
    const WaveplateChain unit = RangedChain(axes, 1.0);
    const WaveplateChain volts = RangedChain(axes, 10.0, M_PI / 10.0);
    GradientProjectionOptions options;
    options.range_aware = true;
    GradientProjectionLaw unit_law(0.5, 0.1, options), volts_law(0.5, 0.1, options);
    for (int trial = 0; trial < 50; ++trial) {
      const int n = static_cast<int>(axes.size());
      ControlVector phi(n);
      for (int i = 0; i < n; ++i) phi[i] = uniform(random);
      const StokesVector s_in =
          StokesVector(uniform(random), uniform(random), uniform(random)).normalized();
      ControlVector unit_delta, volts_delta;
      for (const bool in_volts : {false, true}) {
        const WaveplateChain& chain = in_volts ? volts : unit;
        ControlProblem problem;
        problem.chain = &chain;
        problem.target = &target;
        problem.need_jacobian = true;
        ChainPose pose;
        const ControlVector phi_here = in_volts ? ControlVector(10.0 * phi) : phi;
        chain.ComputePose(phi_here, &pose);
        problem.pose = &pose;
        problem.s_in = s_in;
        UpdateControlProblem(&problem);
        GradientProjectionLaw& law = in_volts ? volts_law : unit_law;
        ASSERT_TRUE(IsUsable(law.ComputeUpdate(problem, in_volts ? &volts_delta : &unit_delta)));
      }
      // Far from a singularity, where both solves are well conditioned.
      if (unit_law.diagnostics().singular_values.min() < 0.2) continue;
      EXPECT_LT((volts_delta - 10.0 * unit_delta).norm(), 1e-9 * (1.0 + volts_delta.norm()))
          << axes << " trial " << trial << ": " << volts_delta.transpose() << " against 10 × "
          << unit_delta.transpose();
    }
  }
}

TEST(GradientProjectionRangeTest, RejectsBadDampingSettings) {
  GradientProjectionOptions options;
  options.max_damping = -1.0;
  EXPECT_THROW(GradientProjectionLaw(0.1, 0.1, options), std::invalid_argument);
  options.max_damping = 0.5;
  options.damping_threshold = 0.0;
  EXPECT_THROW(GradientProjectionLaw(0.1, 0.1, options), std::invalid_argument);
  options.damping_threshold = std::nan("");
  EXPECT_THROW(GradientProjectionLaw(0.1, 0.1, options), std::invalid_argument);
}

}  // namespace
}  // namespace dpc

namespace dpc {
namespace {

class GradientProjectionCurvatureTest : public ::testing::Test, public testing::ControlFixture {
 protected:
  GradientProjectionCurvatureTest() : ControlFixture("3131") {}
};

TEST_F(GradientProjectionCurvatureTest, CorrectionLeavesTheLinearModelsPromiseToSecondOrder) {
  // With step 1 the linear model promises e(φ + Δφ) = 0 (no null-space term); the chain's
  // curvature leaves O(|Δφ|²); the correction removes most of it.
  GradientProjectionOptions options;
  options.curvature_correction = true;
  GradientProjectionLaw plain(1.0, 0.0), corrected(1.0, 0.0, options);
  double plain_sum = 0.0, corrected_sum = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    const ControlVector phi = RandomPhi(0.7);
    const StokesVector s_in = RandomSop();
    // A target 0.05 rad away from the current output.
    const StokesVector here = chain().Output(phi, s_in);
    const Vector3 away = here.cross(RandomSop()).normalized();
    const Target near = Target::Point(RotationAboutAxis(away, 0.05) * here);
    ControlProblem& p = Build(phi, s_in, near);
    ControlVector plain_delta, corrected_delta;
    ASSERT_TRUE(IsUsable(plain.ComputeUpdate(p, &plain_delta)));
    ASSERT_TRUE(IsUsable(corrected.ComputeUpdate(p, &corrected_delta)));
    if (plain.diagnostics().singular_values.min() < 0.5) continue;
    const double plain_error = near.DistanceRad(chain().Output(phi + plain_delta, s_in));
    const double corrected_error = near.DistanceRad(chain().Output(phi + corrected_delta, s_in));
    // The correction uses J at φ, not at φ + Δφ: what remains is O(|Δφ|·r).
    EXPECT_LT(corrected_error, 0.25 * plain_error) << trial;
    plain_sum += plain_error;
    corrected_sum += corrected_error;
  }
  EXPECT_LT(corrected_sum, 0.1 * plain_sum);
}

}  // namespace
}  // namespace dpc
