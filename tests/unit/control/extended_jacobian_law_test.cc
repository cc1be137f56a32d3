#include "dpc/control/extended_jacobian_law.h"

#include <gtest/gtest.h>

#include "dpc/control/gradient_projection_law.h"
#include "support/control_fixture.h"

namespace dpc {
namespace {

using testing::ControlFixture;

class ExtendedJacobianLawTest : public ::testing::Test, public ControlFixture {
 protected:
  ExtendedJacobianLawTest() : ControlFixture("3131") {}

  // Runs a static loop; returns the final φ.
  ControlVector Iterate(ControlLaw& law, ControlVector phi, const StokesVector& s_in,
                        const Target& target, int iterations) {
    for (int k = 0; k < iterations; ++k) {
      ControlVector delta;
      const ControlStatus status = law.ComputeUpdate(Build(phi, s_in, target), &delta);
      EXPECT_TRUE(IsUsable(status)) << "iteration " << k;
      phi += delta;
    }
    return phi;
  }
  double NullSpaceResidual(const ControlVector& phi, const StokesVector& s_in,
                           const Target& target) {
    ControlProblem& p = Build(phi, s_in, target);
    TaskPseudoInverse pinv;
    pinv.Compute(p.task_jacobian);
    ControlVector g;
    pinv.NullSpaceProjection(phi, &g);
    return g.norm();
  }
};

TEST_F(ExtendedJacobianLawTest, ReachesALinearPolarizationAtTheConstrainedOptimum) {
  // The paper's special case: s3 = 0 (any linear polarization), 1 × 4 task.
  const Target linear = Target::Set(Vector3::UnitZ(), 0.0);
  const StokesVector s_in = StokesVector(0.2, 0.3, 0.93).normalized();
  ControlVector phi(4);
  phi << 0.4, -0.3, 0.2, 0.5;
  ExtendedJacobianLaw law(1.0, 1.0);
  phi = Iterate(law, phi, s_in, linear, 30);
  EXPECT_LT(linear.DistanceRad(chain().Output(phi, s_in)), 1e-10);
  // The optimality condition the extra rows enforce: φ has no null-space component.
  EXPECT_LT(NullSpaceResidual(phi, s_in, linear), 1e-8);
}

TEST_F(ExtendedJacobianLawTest, ConvergesFasterThanGradientProjectionToTheSameCondition) {
  const Target linear = Target::Set(Vector3::UnitZ(), 0.0);
  const StokesVector s_in = StokesVector(0.2, 0.3, 0.93).normalized();
  ControlVector start(4);
  start << 0.4, -0.3, 0.2, 0.5;
  ExtendedJacobianLaw extended(1.0, 1.0);
  GradientProjectionLaw gp(1.0, 0.2);
  const ControlVector phi_e = Iterate(extended, start, s_in, linear, 10);
  const ControlVector phi_g = Iterate(gp, start, s_in, linear, 10);
  EXPECT_LT(NullSpaceResidual(phi_e, s_in, linear), 1e-3 * NullSpaceResidual(phi_g, s_in, linear));
}

TEST_F(ExtendedJacobianLawTest, WorksOnAPointTargetThroughTheReducedTask) {
  const Target point = Target::Point(StokesVector(0, 0.6, 0.8));
  const StokesVector s_in = StokesVector(0.5, -0.5, 0.7).normalized();
  ControlVector phi(4);
  phi << 0.3, 0.2, -0.4, 0.1;
  ExtendedJacobianLaw law(1.0, 1.0);
  phi = Iterate(law, phi, s_in, point, 40);
  EXPECT_LT(point.DistanceRad(chain().Output(phi, s_in)), 1e-9);
  EXPECT_LT(NullSpaceResidual(phi, s_in, point), 1e-7);
}

TEST_F(ExtendedJacobianLawTest, ReportsASingularTask) {
  ControlFixture one("1");
  ExtendedJacobianLaw law(1.0, 1.0);
  const Target point = Target::Point(StokesVector(0, 0.6, 0.8));
  ControlVector delta;
  EXPECT_EQ(law.ComputeUpdate(one.Build(one.RandomPhi(), StokesVector::UnitX(), point), &delta),
            ControlStatus::kSingular);
  EXPECT_EQ(delta.norm(), 0.0);
}

TEST_F(ExtendedJacobianLawTest, RejectsBadParameters) {
  EXPECT_THROW(ExtendedJacobianLaw(0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(ExtendedJacobianLaw(1.0, -1.0), std::invalid_argument);
  EXPECT_THROW(ExtendedJacobianLaw(1.0, 1.0, 1e-10, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
