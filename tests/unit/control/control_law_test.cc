#include "dpc/control/control_law.h"

#include <gtest/gtest.h>

#include <string>
#include <string_view>

namespace dpc {
namespace {

TEST(ControlLawTest, EveryStatusHasItsName) {
  EXPECT_EQ(ControlStatusName(ControlStatus::kOk), "ok");
  EXPECT_EQ(ControlStatusName(ControlStatus::kRankDeficient), "rank-deficient");
  EXPECT_EQ(ControlStatusName(ControlStatus::kSingular), "singular");
  EXPECT_EQ(ControlStatusName(ControlStatus::kNotFinite), "not-finite");
}

TEST(ControlLawTest, ValueOutsideTheEnumIsNamedUnknown) {
  EXPECT_EQ(ControlStatusName(static_cast<ControlStatus>(7)), "unknown");
  EXPECT_EQ(ControlStatusName(static_cast<ControlStatus>(-9)), "unknown");
}

TEST(ControlLawTest, NonNegativeStatusesAreUsable) {
  EXPECT_TRUE(IsUsable(ControlStatus::kOk));
  EXPECT_TRUE(IsUsable(ControlStatus::kRankDeficient));
  EXPECT_FALSE(IsUsable(ControlStatus::kSingular));
  EXPECT_FALSE(IsUsable(ControlStatus::kNotFinite));
  // The rule is the sign, not the list: a future degraded (positive) status is usable, a future
  // failure (negative) is not.
  EXPECT_TRUE(IsUsable(static_cast<ControlStatus>(2)));
  EXPECT_FALSE(IsUsable(static_cast<ControlStatus>(-3)));
}

// The interface's defaults: a law needs the full Jacobian unless it says otherwise, Activate
// does nothing, and the diagnostics start zeroed.
class FixedStepLaw final : public ControlLaw {
 public:
  ControlStatus ComputeUpdate(const ControlProblem&, ControlVector* delta_phi) override {
    delta_phi->setConstant(0.5);
    return ControlStatus::kOk;
  }
  std::string_view name() const override { return "fixed"; }
};

TEST(ControlLawTest, InterfaceDefaults) {
  FixedStepLaw law;
  EXPECT_TRUE(law.needs_jacobian());
  EXPECT_EQ(law.name(), "fixed");
  law.Activate(ControlVector::Zero(3));
  const ControlDiagnostics& d = law.diagnostics();
  EXPECT_EQ(d.rank, 0);
  EXPECT_FALSE(d.nullspace_active);
  EXPECT_FALSE(d.loop_suspended);
  EXPECT_EQ(d.resets, 0);
}

}  // namespace
}  // namespace dpc
