// Tests of the field checks the scenario validation shares (field_checks.cc): where they locate
// an error and how they word it, called directly rather than through a scenario.

#include "dpc/config/field_checks.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "dpc/config/scenario_error.h"
#include "dpc/config/scenario_validation.h"
#include "support/scenario_fixture.h"

namespace dpc {
namespace {

using field_checks::Fail;
using field_checks::FormatVector;
using field_checks::RequireAtMost;
using field_checks::RequireAxis;
using field_checks::RequireFinite;
using field_checks::RequireFiniteVector;
using field_checks::RequireNonNegative;
using field_checks::RequirePositive;
using field_checks::RequireRate;
using field_checks::RequireUnitStokes;
using testing::kInf;
using testing::kNaN;

/// What `check` throws as "location: message", or "(accepted)".
template <typename Check>
std::string Outcome(Check check) {
  try {
    check();
  } catch (const ScenarioError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(FieldChecksTest, FailThrowsALocatedScenarioError) {
  try {
    Fail("controller.step", "what is wrong");
    FAIL() << "Fail returned";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(e.location(), "controller.step");
    EXPECT_EQ(e.message(), "what is wrong");
  }
  EXPECT_THROW(Fail("x", "y"), std::invalid_argument);
}

TEST(FieldChecksTest, FormatVectorListsTheComponents) {
  EXPECT_EQ(FormatVector(Vector3(1.0, 0.5, -2.0)), "[1, 0.5, -2]");
}

TEST(FieldChecksTest, ScalarChecksSayWhatTheValueIsAndWhatIsExpected) {
  EXPECT_EQ(Outcome([] { RequireFinite(kNaN, "a.b", "a b must be finite"); }),
            "a.b: nan is not a finite number; a b must be finite");
  EXPECT_EQ(Outcome([] { RequireFinite(-1e300, "a.b", "a b must be finite"); }), "(accepted)");

  EXPECT_EQ(Outcome([] { RequirePositive(0.0, "a.b", "a b must be > 0"); }),
            "a.b: 0 is not > 0; a b must be > 0");
  EXPECT_EQ(Outcome([] { RequirePositive(kInf, "a.b", "a b must be > 0"); }),
            "a.b: inf is not a finite number; a b must be > 0");
  EXPECT_EQ(Outcome([] { RequirePositive(1e-300, "a.b", "a b must be > 0"); }), "(accepted)");

  EXPECT_EQ(Outcome([] { RequireNonNegative(-1.0, "a.b", "a b must be >= 0"); }),
            "a.b: -1 is negative; a b must be >= 0");
  EXPECT_EQ(Outcome([] { RequireNonNegative(-kInf, "a.b", "a b must be >= 0"); }),
            "a.b: -inf is not a finite number; a b must be >= 0");
  EXPECT_EQ(Outcome([] { RequireNonNegative(0.0, "a.b", "a b must be >= 0"); }), "(accepted)");

  EXPECT_EQ(Outcome([] { RequireAtMost(2.5, 2.0, "a.b", "a b"); }),
            "a.b: 2.5 is above 2; a b must be at most that");
  EXPECT_EQ(Outcome([] { RequireAtMost(2.0, 2.0, "a.b", "a b"); }), "(accepted)");
}

TEST(FieldChecksTest, RateIsNonNegativeAndBelowPiPerSample) {
  EXPECT_EQ(Outcome([] { RequireRate(-1.0, 100.0, "r"); }),
            "r: -1 rad/s is negative; a rotation rate must be >= 0 (use the axis direction to "
            "reverse)");
  EXPECT_EQ(Outcome([] { RequireRate(kNaN, 100.0, "r"); }),
            "r: nan is not a finite number; a rotation rate must be finite and >= 0 rad/s");
  EXPECT_EQ(Outcome([] { RequireRate(400.0, 100.0, "r"); }),
            "r: 400 rad/s at 100 Hz: 4 rad per sample exceeds π: the simulation cannot resolve "
            "it; raise simulation.sample_rate_hz above 127.324 Hz");
  EXPECT_EQ(Outcome([] { RequireRate(300.0, 100.0, "r"); }), "(accepted)");
  EXPECT_EQ(Outcome([] { RequireRate(0.0, 100.0, "r"); }), "(accepted)");
}

TEST(FieldChecksTest, NonFiniteVectorComponentIsNamed) {
  EXPECT_EQ(Outcome([] { RequireFiniteVector(Vector3(0.0, 0.0, kNaN), "v", "finite"); }),
            "v.s3: nan is not a finite number; finite");
  EXPECT_EQ(Outcome([] { RequireFiniteVector(Vector3(kInf, 0.0, 0.0), "v", "finite"); }),
            "v.s1: inf is not a finite number; finite");
  EXPECT_EQ(Outcome([] { RequireFiniteVector(Vector3(1.0, 2.0, 3.0), "v", "finite"); }),
            "(accepted)");
}

TEST(FieldChecksTest, AxisNeedsALength) {
  EXPECT_EQ(Outcome([] { RequireAxis(Vector3::Zero(), "a"); }),
            "a: zero-length axis [0, 0, 0] (|axis| = 0); an axis needs a direction: any vector "
            "with |axis| >= 1e-09 (it is normalized)");
  EXPECT_EQ(Outcome([] { RequireAxis(Vector3(0.0, kNaN, 1.0), "a"); }),
            "a.s2: nan is not a finite number; an axis component must be finite");
  EXPECT_EQ(Outcome([] { RequireAxis(Vector3(kMinAxisLength, 0.0, 0.0), "a"); }), "(accepted)");
}

TEST(FieldChecksTest, UnitStokesIsWithinTheTolerance) {
  EXPECT_EQ(Outcome([] { RequireUnitStokes(StokesVector(0.0, 0.6, 0.9), "s"); }),
            "s: [0, 0.6, 0.9] has |S| = 1.08166538; a fully polarized SOP is a unit Stokes "
            "vector (|S| within 1e-06 of 1)");
  EXPECT_EQ(Outcome([] { RequireUnitStokes(StokesVector(0.0, kInf, 0.0), "s"); }),
            "s.s2: inf is not a finite number; a Stokes component must be finite");
  EXPECT_EQ(Outcome([] { RequireUnitStokes(StokesVector(1.0 + 0.5e-6, 0.0, 0.0), "s"); }),
            "(accepted)");
  EXPECT_NE(Outcome([] { RequireUnitStokes(StokesVector(1.0 + 2e-6, 0.0, 0.0), "s"); }),
            "(accepted)");
}

}  // namespace
}  // namespace dpc
