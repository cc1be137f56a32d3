// Tests of the device part of the scenario validation (device_validation.cc): the stages,
// their control maps and ranges, and the control count. Each test breaks one field of the
// paper's scenario and checks where ValidateScenario locates the error.

#include "dpc/config/scenario_validation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "support/scenario_fixture.h"

namespace dpc {
namespace {

using ::testing::HasSubstr;
using testing::kInf;
using testing::kNaN;

class DeviceValidationTest : public testing::ScenarioFixture {
 protected:
  static ControlMapConfig Table(std::vector<double> control, std::vector<double> angle_rad) {
    ControlMapConfig map;
    map.kind = ControlMapConfig::Kind::kTable;
    map.table_control = std::move(control);
    map.table_angle_rad = std::move(angle_rad);
    return map;
  }
  static ControlMapConfig Polynomial(std::vector<double> coefficients_rad) {
    ControlMapConfig map;
    map.kind = ControlMapConfig::Kind::kPolynomial;
    map.coefficients_rad = std::move(coefficients_rad);
    return map;
  }
  /// Tables at 20 and 40 °C, operating at 30 °C.
  static ControlMapConfig ByTemperature() {
    ControlMapConfig map;
    map.kind = ControlMapConfig::Kind::kTablesByCondition;
    map.condition = ControlMapConfig::Condition::kTemperatureC;
    map.operating_point = 30.0;
    map.condition_tables = {{20.0, {0, 1, 2}, {0, 1, 3}}, {40.0, {0, 1, 2}, {0, 1.1, 3.3}}};
    return map;
  }
  /// A rotatable quarter-wave plate: θ fixed at π/2, ϕ controlled.
  static StageConfig QuarterWavePlate() {
    StageConfig stage;
    stage.kind = StageConfig::Kind::kAdjustableAxis;
    stage.retardance.fixed_rad = M_PI / 2;
    stage.orientation.controlled = true;
    return stage;
  }
};

// ---- Stages.

TEST_F(DeviceValidationTest, ZeroStagesAreRejected) {
  scenario_.stages.clear();
  EXPECT_EQ(ErrorLocation(), "stages");
  EXPECT_EQ(ErrorMessage(), "0 stages; a chain needs 1 to 16");
}

TEST_F(DeviceValidationTest, SeventeenStagesAreRejected) {
  scenario_.stages = StagesFromAxes("13131313131313131");
  scenario_.controller.method = ControlMethod::kPseudoInverse;
  EXPECT_EQ(ErrorLocation(), "stages");
  EXPECT_THAT(ErrorMessage(), HasSubstr("17 stages"));
}

TEST_F(DeviceValidationTest, SixteenStagesOfTwoControlsAreTheLimit) {
  StageConfig both = QuarterWavePlate();
  both.retardance.controlled = true;
  scenario_.stages.assign(16, both);
  EXPECT_EQ(ScenarioControlCount(scenario_.stages), kMaxControls);
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(DeviceValidationTest, ZeroLengthAxisIsRejected) {
  scenario_.stages[2].axis = Vector3::Zero();
  EXPECT_EQ(ErrorLocation(), "stages[2].axis_vector");
  EXPECT_THAT(ErrorMessage(), HasSubstr("zero-length axis"));
}

TEST_F(DeviceValidationTest, AnyNonZeroAxisIsAccepted) {
  scenario_.stages[2].axis = Vector3(0.0, 3.0, 4.0);
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(DeviceValidationTest, NonFiniteAxisComponentIsNamed) {
  scenario_.stages[1].axis = Vector3(0.0, kInf, 1.0);
  EXPECT_EQ(ErrorLocation(), "stages[1].axis_vector.s2");
}

// ---- Control maps.

TEST_F(DeviceValidationTest, LinearMapNeedsANonZeroSlope) {
  scenario_.stages[0].map.rad_per_unit = 0.0;
  EXPECT_EQ(ErrorLocation(), "stages[0].map.linear.rad_per_unit");
}

TEST_F(DeviceValidationTest, LinearMapOffsetMustBeFinite) {
  scenario_.stages[0].map.offset_rad = kNaN;
  EXPECT_EQ(ErrorLocation(), "stages[0].map.linear.offset_rad");
}

TEST_F(DeviceValidationTest, PolynomialNeedsTwoToSixteenCoefficients) {
  scenario_.stages[1].map = Polynomial({0.5});
  EXPECT_EQ(ErrorLocation(), "stages[1].map.polynomial.coefficients_rad");
  scenario_.stages[1].map = Polynomial(std::vector<double>(17, 1.0));
  EXPECT_EQ(ErrorLocation(), "stages[1].map.polynomial.coefficients_rad");
  scenario_.stages[1].map = Polynomial(std::vector<double>(16, 1.0));
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(DeviceValidationTest, PolynomialMustNotBeConstant) {
  scenario_.stages[1].map = Polynomial({0.5, 0.0, 0.0});
  EXPECT_EQ(ErrorLocation(), "stages[1].map.polynomial.coefficients_rad");
  EXPECT_THAT(ErrorMessage(), HasSubstr("constant"));
}

TEST_F(DeviceValidationTest, NonMonotonicLookupTableNamesTheFirstOffendingIndex) {
  scenario_.stages[0].map = Table({0, 1, 2, 3, 4}, {0, 1, 3, 2, 1});
  EXPECT_EQ(ErrorLocation(), "stages[0].map.table.angle_rad[3]");
  EXPECT_EQ(ErrorMessage(),
            "2 after 3 (the table increases before); a lookup table must be strictly monotonic");
}

TEST_F(DeviceValidationTest, DecreasingLookupTableIsAccepted) {
  scenario_.stages[0].map = Table({0, 1, 2}, {3, 1, -2});
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(DeviceValidationTest, FlatLookupTableStartIsRejected) {
  scenario_.stages[0].map = Table({0, 1, 2}, {1, 1, 2});
  EXPECT_EQ(ErrorLocation(), "stages[0].map.table.angle_rad[1]");
}

TEST_F(DeviceValidationTest, LookupTableControlMustIncrease) {
  scenario_.stages[0].map = Table({0, 1, 1, 2}, {0, 1, 2, 3});
  EXPECT_EQ(ErrorLocation(), "stages[0].map.table.control[2]");
}

TEST_F(DeviceValidationTest, LookupTableColumnsMustPairUp) {
  scenario_.stages[0].map = Table({0, 1, 2}, {0, 1});
  EXPECT_EQ(ErrorLocation(), "stages[0].map.table");
}

TEST_F(DeviceValidationTest, LookupTableNeedsTwoPoints) {
  scenario_.stages[0].map = Table({0}, {0});
  EXPECT_EQ(ErrorLocation(), "stages[0].map.table.control");
}

TEST_F(DeviceValidationTest, LookupTableValuesMustBeFinite) {
  scenario_.stages[0].map = Table({0, 1, 2}, {0, 1, kNaN});
  EXPECT_EQ(ErrorLocation(), "stages[0].map.table.angle_rad[2]");
}

// ---- Tables by condition.

TEST_F(DeviceValidationTest, TablesByTemperatureAreAccepted) {
  scenario_.stages[0].map = ByTemperature();
  EXPECT_EQ(ErrorLocation(), "(valid)");
}

TEST_F(DeviceValidationTest, AnOperatingPointOutsideTheCalibratedSpanIsRejected) {
  scenario_.stages[0].map = ByTemperature();
  scenario_.stages[0].map.operating_point = 45.0;
  EXPECT_EQ(ErrorLocation(), "stages[0].map.tables_by_condition.operating_temperature_c");
  EXPECT_EQ(ErrorMessage(),
            "45 °C is outside the calibrated 20–40 °C: a calibration is not extrapolated (calibrate at this "
            "temperature too)");
  scenario_.stages[0].map.condition = ControlMapConfig::Condition::kWavelengthNm;
  scenario_.stages[0].map.operating_point = kNaN;
  EXPECT_EQ(ErrorLocation(), "stages[0].map.tables_by_condition.operating_wavelength_nm");
}

TEST_F(DeviceValidationTest, TablesByConditionNeedTwoToSixteenTablesInIncreasingOrder) {
  scenario_.stages[0].map = ByTemperature();
  scenario_.stages[0].map.condition_tables.resize(1);
  EXPECT_EQ(ErrorLocation(), "stages[0].map.tables_by_condition.tables");
  scenario_.stages[0].map = ByTemperature();
  scenario_.stages[0].map.condition_tables.resize(17, scenario_.stages[0].map.condition_tables[1]);
  EXPECT_EQ(ErrorLocation(), "stages[0].map.tables_by_condition.tables");
  scenario_.stages[0].map = ByTemperature();
  scenario_.stages[0].map.condition_tables[1].condition = 20.0;
  EXPECT_EQ(ErrorLocation(), "stages[0].map.tables_by_condition.tables[1].temperature_c");
  EXPECT_THAT(ErrorMessage(), HasSubstr("strictly increasing"));
  scenario_.stages[0].map.condition_tables[1].condition = kInf;
  EXPECT_EQ(ErrorLocation(), "stages[0].map.tables_by_condition.tables[1].temperature_c");
  scenario_.stages[0].map = ByTemperature();
  scenario_.stages[0].map.condition = ControlMapConfig::Condition::kWavelengthNm;
  scenario_.stages[0].map.condition_tables[0].condition = -20.0;
  EXPECT_EQ(ErrorLocation(), "stages[0].map.tables_by_condition.tables[0].wavelength_nm");
  EXPECT_THAT(ErrorMessage(), HasSubstr("positive"));
}

TEST_F(DeviceValidationTest, EachTableOfACondititionIsCheckedAsATable) {
  scenario_.stages[0].map = ByTemperature();
  scenario_.stages[0].map.condition_tables[1].control = {0, 2, 1};
  EXPECT_EQ(ErrorLocation(), "stages[0].map.tables_by_condition.tables[1].table.control[2]");
  scenario_.stages[0].map = ByTemperature();
  scenario_.stages[0].map.condition_tables[0].angle_rad = {0, 1, kNaN};
  EXPECT_EQ(ErrorLocation(), "stages[0].map.tables_by_condition.tables[0].table.angle_rad[2]");
}

TEST_F(DeviceValidationTest, TablesByConditionMustRunTheSameWay) {
  scenario_.stages[0].map = ByTemperature();
  scenario_.stages[0].map.condition_tables[1].angle_rad = {3, 1, 0};
  EXPECT_EQ(ErrorLocation(), "stages[0].map.tables_by_condition.tables[1].table.angle_rad");
  EXPECT_THAT(ErrorMessage(), HasSubstr("decreases while tables[0] increases"));
}

// ---- Ranges.

TEST_F(DeviceValidationTest, EmptyRangeIsRejected) {
  scenario_.stages[1].range = ControlRange{1.0, 1.0};
  EXPECT_EQ(ErrorLocation(), "stages[1].range");
}

TEST_F(DeviceValidationTest, NonFiniteRangeLimitIsNamed) {
  scenario_.stages[1].range = ControlRange{-kInf, 1.0};
  EXPECT_EQ(ErrorLocation(), "stages[1].range.min");
}

// ---- Adjustable-axis stages.

TEST_F(DeviceValidationTest, AdjustableAxisStageNeedsAControl) {
  scenario_.stages[1] = QuarterWavePlate();
  EXPECT_EQ(ErrorLocation(), "(valid)");
  scenario_.stages[1].orientation.controlled = false;
  EXPECT_EQ(ErrorLocation(), "stages[1].adjustable_axis");
}

TEST_F(DeviceValidationTest, AdjustableAxisFixedAngleMustBeFinite) {
  scenario_.stages[1] = QuarterWavePlate();
  scenario_.stages[1].retardance.fixed_rad = kNaN;
  EXPECT_EQ(ErrorLocation(), "stages[1].adjustable_axis.retardance.fixed_rad");
}

TEST_F(DeviceValidationTest, NaNInANestedMapIsNamedByItsFullPath) {
  scenario_.stages[0] = QuarterWavePlate();
  scenario_.stages[0].orientation.map = Polynomial({0.0, 2.0, 0.5});
  EXPECT_EQ(ErrorLocation(), "(valid)");
  scenario_.stages[0].orientation.map.coefficients_rad[1] = kNaN;
  EXPECT_EQ(ErrorLocation(),
            "stages[0].adjustable_axis.orientation.controlled.map.polynomial.coefficients_rad[1]");
}

TEST_F(DeviceValidationTest, AdjustableAxisRangeIsChecked) {
  scenario_.stages[0] = QuarterWavePlate();
  scenario_.stages[0].orientation.range = ControlRange{2.0, -2.0};
  EXPECT_EQ(ErrorLocation(), "stages[0].adjustable_axis.orientation.controlled.range");
}

// ---- Control count.

TEST_F(DeviceValidationTest, ControlCountCountsControlledAngles) {
  EXPECT_EQ(ScenarioControlCount(scenario_.stages), 3);
  scenario_.stages.push_back(QuarterWavePlate());
  EXPECT_EQ(ScenarioControlCount(scenario_.stages), 4);
  scenario_.stages.back().retardance.controlled = true;
  EXPECT_EQ(ScenarioControlCount(scenario_.stages), 5);
  EXPECT_EQ(ScenarioControlCount({}), 0);
}

}  // namespace
}  // namespace dpc
