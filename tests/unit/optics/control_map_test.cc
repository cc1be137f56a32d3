#include "dpc/optics/control_map.h"

#include <gtest/gtest.h>

#include <cmath>

namespace dpc {
namespace {

TEST(ControlMapTest, LinearDefaultIsPiPerUnit) {
  const ControlMap map = ControlMap::Linear();
  EXPECT_DOUBLE_EQ(map.AngleRad(1.0), M_PI);
  EXPECT_DOUBLE_EQ(map.AngleRad(-0.5), -M_PI / 2);
  EXPECT_DOUBLE_EQ(map.DerivativeRadPerUnit(0.3), M_PI);
  EXPECT_TRUE(map.has_analytic_derivative());
}

TEST(ControlMapTest, LinearWithOffset) {
  const ControlMap map = ControlMap::Linear(2.0, 0.5);
  EXPECT_DOUBLE_EQ(map.AngleRad(1.0), 2.5);
  EXPECT_DOUBLE_EQ(map.DerivativeRadPerUnit(7.0), 2.0);
}

TEST(ControlMapTest, LinearRejectsZeroSlopeAndNonFinite) {
  EXPECT_THROW(ControlMap::Linear(0.0), std::invalid_argument);
  EXPECT_THROW(ControlMap::Linear(NAN), std::invalid_argument);
  EXPECT_THROW(ControlMap::Linear(1.0, INFINITY), std::invalid_argument);
}

TEST(ControlMapTest, PolynomialValueAndDerivative) {
  // θ = 0.1 + 3φ − 0.5φ² + 0.2φ³
  const ControlMap map = ControlMap::Polynomial({0.1, 3.0, -0.5, 0.2});
  for (double x : {-1.5, 0.0, 0.7, 2.0}) {
    EXPECT_NEAR(map.AngleRad(x), 0.1 + 3 * x - 0.5 * x * x + 0.2 * x * x * x, 1e-14);
    EXPECT_NEAR(map.DerivativeRadPerUnit(x), 3 - x + 0.6 * x * x, 1e-14);
  }
}

TEST(ControlMapTest, PolynomialRejectsBadCoefficients) {
  EXPECT_THROW(ControlMap::Polynomial({}), std::invalid_argument);
  EXPECT_THROW(ControlMap::Polynomial({1.0}), std::invalid_argument);       // constant
  EXPECT_THROW(ControlMap::Polynomial({1.0, 0.0}), std::invalid_argument);  // constant
  EXPECT_THROW(ControlMap::Polynomial({0.0, NAN}), std::invalid_argument);
  EXPECT_THROW(ControlMap::Polynomial(std::vector<double>(17, 1.0)), std::invalid_argument);
  EXPECT_NO_THROW(ControlMap::Polynomial(std::vector<double>(16, 1.0)));
}

TEST(ControlMapTest, TableInterpolatesAndExtrapolatesLinearly) {
  const ControlMap map = ControlMap::Table({-1.0, 0.0, 2.0}, {-3.0, 0.0, 4.0});
  EXPECT_DOUBLE_EQ(map.AngleRad(-0.5), -1.5);
  EXPECT_DOUBLE_EQ(map.AngleRad(1.0), 2.0);
  EXPECT_DOUBLE_EQ(map.AngleRad(2.0), 4.0);
  EXPECT_DOUBLE_EQ(map.AngleRad(3.0), 6.0);    // last segment extended
  EXPECT_DOUBLE_EQ(map.AngleRad(-2.0), -6.0);  // first segment extended
  EXPECT_FALSE(map.has_analytic_derivative());
  EXPECT_NEAR(map.DerivativeRadPerUnit(-0.5), 3.0, 1e-6);
  EXPECT_NEAR(map.DerivativeRadPerUnit(1.0), 2.0, 1e-6);
  EXPECT_NEAR(map.DerivativeRadPerUnit(0.0), 2.5, 1e-6);  // mean of the slopes at a knot
  ASSERT_TRUE(map.TableSpan().has_value());
  EXPECT_EQ(map.TableSpan()->first, -1.0);
  EXPECT_EQ(map.TableSpan()->second, 2.0);
}

TEST(ControlMapTest, DecreasingTableIsMonotonicToo) {
  EXPECT_NO_THROW(ControlMap::Table({0.0, 1.0, 2.0}, {1.0, 0.0, -2.0}));
}

TEST(ControlMapTest, TableRejectsNonMonotonicAndNamesTheIndex) {
  try {
    ControlMap::Table({0.0, 1.0, 2.0, 3.0}, {0.0, 1.0, 3.0, 2.0});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("angle_rad[3]"), std::string::npos) << e.what();
  }
  try {
    ControlMap::Table({0.0, 2.0, 1.0}, {0.0, 1.0, 2.0});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("control[2]"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ControlMap::Table({0.0, 0.0}, {0.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(ControlMap::Table({0.0, 1.0}, {1.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(ControlMap::Table({0.0}, {0.0}), std::invalid_argument);
  EXPECT_THROW(ControlMap::Table({0.0, 1.0}, {0.0}), std::invalid_argument);
  EXPECT_THROW(ControlMap::Table({0.0, NAN}, {0.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(ControlMap::Table(std::vector<double>(4097), std::vector<double>(4097)),
               std::invalid_argument);
}

TEST(ControlMapTest, ControlForAngleInvertsEveryKind) {
  const ControlMap linear = ControlMap::Linear();
  ASSERT_TRUE(linear.ControlForAngle(M_PI / 2, -1, 1).has_value());
  EXPECT_NEAR(*linear.ControlForAngle(M_PI / 2, -1, 1), 0.5, 1e-15);
  EXPECT_FALSE(linear.ControlForAngle(3 * M_PI, -1, 1).has_value());

  const ControlMap poly = ControlMap::Polynomial({0.0, 3.0, 0.0, 0.1});  // monotonic
  const auto x = poly.ControlForAngle(poly.AngleRad(0.8), -2, 2);
  ASSERT_TRUE(x.has_value());
  EXPECT_NEAR(*x, 0.8, 1e-12);

  const ControlMap folded = ControlMap::Polynomial({0.0, 0.0, 1.0});  // θ = φ², not monotonic
  EXPECT_FALSE(folded.ControlForAngle(0.25, -1, 1).has_value());

  const ControlMap table = ControlMap::Table({0.0, 1.0, 2.0}, {2.0, 1.0, -1.0});
  const auto y = table.ControlForAngle(0.0, 0.0, 2.0);
  ASSERT_TRUE(y.has_value());
  EXPECT_NEAR(*y, 1.5, 1e-12);
}

TEST(ControlMapTest, DescribeNamesTheKind) {
  EXPECT_EQ(ControlMap::Linear(2.0).Describe(), "linear 2 rad/unit");
  EXPECT_EQ(ControlMap::Polynomial({0, 1, 2}).Describe(), "polynomial degree 2");
  EXPECT_EQ(ControlMap::Table({0, 1}, {0, 1}).Describe(), "table 2 points");
}

}  // namespace
}  // namespace dpc
