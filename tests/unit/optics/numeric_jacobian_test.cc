#include "dpc/optics/numeric_jacobian.h"

#include <gtest/gtest.h>

#include <cmath>

#include "dpc/optics/rotation.h"

namespace dpc {
namespace {

TEST(NumericJacobianTest, OneStageColumnIsKTimesAxisCrossOutput) {
  const WaveplateChain chain = WaveplateChain::FromAxes("3");
  ControlVector phi(1);
  phi << 0.3;
  const StokesVector s_in(1, 0, 0);
  const Matrix3X j = NumericJacobian(chain, phi, s_in);
  const Vector3 s_out = R3(M_PI * 0.3) * s_in;
  EXPECT_LT((j.col(0) - M_PI * Vector3::UnitZ().cross(s_out)).norm(), 1e-9);
}

TEST(NumericJacobianTest, ErrorIsSecondOrderInTheStep) {
  const WaveplateChain chain = WaveplateChain::FromAxes("131");
  ControlVector phi(3);
  phi << 0.2, -0.4, 0.9;
  const StokesVector s_in = StokesVector(0.3, 0.5, -0.2).normalized();
  const Matrix3X exact = chain.Jacobian(phi, s_in);
  const double e1 = (NumericJacobian(chain, phi, s_in, 1e-2) - exact).norm();
  const double e2 = (NumericJacobian(chain, phi, s_in, 5e-3) - exact).norm();
  EXPECT_NEAR(e1 / e2, 4.0, 0.05);  // halving h quarters the error
}

TEST(NumericJacobianTest, RejectsBadArguments) {
  const WaveplateChain chain = WaveplateChain::FromAxes("13");
  ControlVector phi(3);
  phi.setZero();
  EXPECT_THROW(NumericJacobian(chain, phi, StokesVector::UnitX()), std::invalid_argument);
  phi.resize(2);
  phi.setZero();
  EXPECT_THROW(NumericJacobian(chain, phi, StokesVector::UnitX(), 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
