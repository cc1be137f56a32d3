#include "dpc/cli/command_line.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace dpc::cli {
namespace {

TEST(EditDistanceTest, CountsInsertionsDeletionsAndSubstitutions) {
  EXPECT_EQ(EditDistance("", ""), 0u);
  EXPECT_EQ(EditDistance("sim", "sim"), 0u);
  EXPECT_EQ(EditDistance("simm", "sim"), 1u);
  EXPECT_EQ(EditDistance("--metod", "--method"), 1u);
  EXPECT_EQ(EditDistance("kitten", "sitting"), 3u);
  EXPECT_EQ(EditDistance("", "abc"), 3u);
}

class UnknownNameTest : public ::testing::Test {
 protected:
  void SetUp() override {
    app_.name("dpc");
    sim_ = app_.add_subcommand("sim", "");
    sim_->add_option("scenario", scenario_);
    sim_->add_option("--method", method_);
    auto* topic = app_.add_subcommand("topic", "");
    auto* echo = topic->add_subcommand("echo", "");
    echo->add_option("topic", scenario_);
    echo->add_flag("--json", json_);
    AddVersionFlag(app_, "dpc");
  }
  std::string Problem(const std::vector<std::string>& args) { return UnknownNameProblem(app_, args); }

  CLI::App app_{"test"};
  CLI::App* sim_ = nullptr;
  std::string scenario_, method_;
  bool json_ = false;
};

TEST_F(UnknownNameTest, KnownCommandLinesHaveNoProblem) {
  EXPECT_EQ(Problem({"sim", "file.pbtxt", "--method", "gp"}), "");
  EXPECT_EQ(Problem({"sim", "--method=gp"}), "");
  EXPECT_EQ(Problem({"topic", "echo", "dpc_waveplate_state", "--json"}), "");
  EXPECT_EQ(Problem({"--version"}), "");
  EXPECT_EQ(Problem({"sim", "--help"}), "");
  EXPECT_EQ(Problem({"sim", "--", "--not-an-option"}), "");  // positional after --
  EXPECT_EQ(Problem({"sim", "-x"}), "");                      // short flags: CLI11 judges
}

TEST_F(UnknownNameTest, UnknownNamesAreNamedWithTheNearestKnownOne) {
  EXPECT_EQ(Problem({"simm"}), "dpc: unknown command 'simm' (did you mean sim?); the commands are sim, topic");
  EXPECT_EQ(Problem({"sim", "--metod", "gp"}), "dpc sim: unknown option --metod (did you mean --method?)");
  EXPECT_EQ(Problem({"topic", "ech"}), "dpc topic: unknown command 'ech' (did you mean echo?); the commands are echo");
  EXPECT_EQ(Problem({"topic", "echo", "x", "--jsn"}), "dpc topic echo: unknown option --jsn (did you mean --json?)");
  // Nothing near: no suggestion.
  EXPECT_EQ(Problem({"sim", "--seed"}), "dpc sim: unknown option --seed");
  EXPECT_EQ(Problem({"zz"}), "dpc: unknown command 'zz'; the commands are sim, topic");
}

TEST(VersionTextTest, NamesTheProgramTheProjectAndFastDds) {
  const std::string text = VersionText("dpc-driver");
  EXPECT_EQ(text.rfind("dpc-driver 0.", 0), 0u) << text;
  EXPECT_NE(text.find("Fast DDS 2."), std::string::npos) << text;
}

TEST(NumberValidatorTest, TakesFiniteNumbersInRangeAndSaysWhatIsWrongWithTheRest) {
  const auto problem = [](const CLI::Validator& validator, std::string text) { return validator(text); };
  for (const char* good : {"0", "0.0", "1e5", "2.5", "1e308"}) {
    EXPECT_EQ(problem(NonNegativeNumber(), good), "") << good;
  }
  for (const char* good : {"1e-300", "1e-320", "3", "0.5"}) EXPECT_EQ(problem(PositiveNumber(), good), "") << good;
  EXPECT_EQ(problem(NonNegativeNumber(), "nan"), "'nan' is not a finite number");
  EXPECT_EQ(problem(NonNegativeNumber(), "-inf"), "'-inf' is not a finite number");
  EXPECT_EQ(problem(NonNegativeNumber(), "1e999"), "'1e999' is not a finite number");  // beyond double's range
  EXPECT_EQ(problem(NonNegativeNumber(), ""), "'' is not a number");
  EXPECT_EQ(problem(NonNegativeNumber(), "5x"), "'5x' is not a number");
  EXPECT_EQ(problem(NonNegativeNumber(), "-1"), "'-1' is below 0");
  EXPECT_EQ(problem(PositiveNumber(), "0"), "'0' is not above 0");
  EXPECT_EQ(problem(PositiveNumber(), "NaN"), "'NaN' is not a finite number");
  const CLI::Validator range = NumberIn(0.1, 600.0);
  for (const char* good : {"0.1", "600", "5"}) EXPECT_EQ(problem(range, good), "") << good;
  EXPECT_EQ(problem(range, "nan"), "'nan' is not a finite number");  // CLI::Range takes it
  EXPECT_EQ(problem(range, "inf"), "'inf' is not a finite number");
  EXPECT_EQ(problem(range, "0.05"), "'0.05' is not in [0.1, 600]");
  EXPECT_EQ(problem(range, "601"), "'601' is not in [0.1, 600]");
  EXPECT_EQ(problem(range, "x"), "'x' is not a number");
  EXPECT_EQ(range.get_description(), "FLOAT in [0.1 - 600]");
}

TEST(ParseSeedListTest, TakesValuesAndRanges) {
  EXPECT_EQ(ParseSeedList("3"), (std::vector<uint64_t>{3}));
  EXPECT_EQ(ParseSeedList("1-4"), (std::vector<uint64_t>{1, 2, 3, 4}));
  EXPECT_EQ(ParseSeedList("1,2,7-8"), (std::vector<uint64_t>{1, 2, 7, 8}));
  EXPECT_EQ(ParseSeedList("18446744073709551615"), (std::vector<uint64_t>{18446744073709551615ull}));
  EXPECT_EQ(ParseSeedList("18446744073709551614-18446744073709551615").size(), 2u);  // no wrap at the end
}

TEST(ParseSeedListTest, RefusesWhatIsNotASeedList) {
  for (const char* bad : {"", "-1", "1,,2", "a", "3-1", "1-", "1-2-3", "18446744073709551616", "1.5", "1, 2"}) {
    EXPECT_THROW(ParseSeedList(bad), std::invalid_argument) << bad;
  }
  EXPECT_THROW(ParseSeedList("1-20001"), std::invalid_argument);
  EXPECT_THROW(ParseSeedList("1-5,1-5", 8), std::invalid_argument);
}

}  // namespace
}  // namespace dpc::cli
