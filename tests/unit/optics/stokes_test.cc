#include "dpc/optics/stokes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace dpc {
namespace {

TEST(StokesTest, UnitCheckAcceptsUnitAndRejectsOthers) {
  EXPECT_TRUE(IsUnitStokes(StokesVector(0.0, 0.6, 0.8)));
  EXPECT_FALSE(IsUnitStokes(StokesVector(0.0, 0.6, 0.9)));
  EXPECT_FALSE(IsUnitStokes(StokesVector(NAN, 0.0, 1.0)));
  EXPECT_FALSE(IsUnitStokes(StokesVector(INFINITY, 0.0, 0.0)));
}

TEST(StokesTest, RequireUnitNamesTheVectorAndTheNorm) {
  try {
    RequireUnitStokes(StokesVector(0.0, 0.6, 0.9), "target point");
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("target point"), std::string::npos) << what;
    EXPECT_NE(what.find("1.08166538"), std::string::npos) << what;
  }
  EXPECT_THROW(RequireUnitStokes(StokesVector(NAN, 0, 1), "s"), std::invalid_argument);
  EXPECT_NO_THROW(RequireUnitStokes(StokesVector(1, 0, 0), "s"));
}

TEST(StokesTest, SphereAngleIsAccurateAtZeroRightAngleAndAntipode) {
  const StokesVector a(1, 0, 0);
  EXPECT_NEAR(SphereAngleRad(a, a), 0.0, 1e-15);
  EXPECT_NEAR(SphereAngleRad(a, StokesVector(0, 1, 0)), M_PI / 2, 1e-15);
  EXPECT_NEAR(SphereAngleRad(a, -a), M_PI, 1e-15);
  const double tiny = 1e-9;  // acos(cos(1e-9)) would return 0 here
  EXPECT_NEAR(SphereAngleRad(a, StokesVector(std::cos(tiny), std::sin(tiny), 0)), tiny, 1e-20);
  const double near_pi = M_PI - 1e-9;
  EXPECT_NEAR(SphereAngleRad(a, StokesVector(std::cos(near_pi), std::sin(near_pi), 0)), near_pi,
              1e-15);
}

TEST(StokesTest, PolarizerLeakIsZeroAlignedAndOneCrossed) {
  const StokesVector s(0, 0.6, 0.8);
  EXPECT_DOUBLE_EQ(PolarizerLeak(s, s), 0.0);
  EXPECT_DOUBLE_EQ(PolarizerLeak(-s, s), 1.0);
  EXPECT_DOUBLE_EQ(PolarizerLeak(StokesVector(1, 0, 0), s), 0.5);
}

TEST(StokesTest, RenormalizeRemovesSmallDrift) {
  StokesVector s = StokesVector(0.3, -0.4, std::sqrt(0.75)) * (1.0 + 1e-6);
  RenormalizeNearUnit(&s);
  EXPECT_NEAR(s.norm(), 1.0, 1e-11);
}

TEST(StokesTest, TangentBasisIsRightHandedOrthonormalEverywhere) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  std::vector<StokesVector> points{{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, -1, 0}};
  for (int i = 0; i < 1000; ++i) {
    points.push_back(StokesVector(normal(rng), normal(rng), normal(rng)).normalized());
  }
  for (const auto& s : points) {
    Vector3 e1, e2;
    TangentBasis(s, &e1, &e2);
    EXPECT_NEAR(e1.norm(), 1.0, 1e-12);
    EXPECT_NEAR(e2.norm(), 1.0, 1e-12);
    EXPECT_NEAR(e1.dot(e2), 0.0, 1e-12);
    EXPECT_NEAR(e1.dot(s), 0.0, 1e-12);
    EXPECT_LT((e1.cross(e2) - s).norm(), 1e-12) << FormatStokes(s);
  }
}

}  // namespace
}  // namespace dpc
