#include "plot_command.h"

#include <CLI/CLI.hpp>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "dpc/sim/closed_loop_simulator.h"
#include "dpc/sim/trace_writer.h"
#include "dpc/cli/exit_code.h"
#include "trace_format.h"

namespace dpc::tools {
namespace {

namespace fs = std::filesystem;

class PlotCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = fs::temp_directory_path() /
                 ("dpc_plot_command_test_" +
                  std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(directory_);
    fs::create_directories(directory_);
    command_ = AddPlotCommand(app_, &options_);
    trace_ = PathIn("trace.csv");
    png_ = PathIn("figure.png");
  }
  void TearDown() override { fs::remove_all(directory_); }

  void Parse(std::vector<std::string> args) {
    args.insert(args.begin(), {"dpc", "plot"});
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    app_.parse(static_cast<int>(argv.size()), argv.data());
  }

  cli::ExitCode Run() {
    ::testing::internal::CaptureStdout();
    ::testing::internal::CaptureStderr();
    const cli::ExitCode code = RunPlotCommand(options_);
    out_ = ::testing::internal::GetCapturedStdout();
    err_ = ::testing::internal::GetCapturedStderr();
    return code;
  }

  // A 200-row trace with the metadata `dpc sim --trace` writes (`magic`: with its first line).
  void WriteTrace(bool magic) {
    ScenarioConfig scenario = PaperScenario("131");
    scenario.simulation.duration_s = 1e-4;
    scenario.controller.activation_s = 4e-5;
    const ClosedLoopSimulator simulator(scenario);
    std::vector<std::string> comments = TraceHeaderComments(simulator, 25);
    if (!magic) comments.erase(comments.begin());
    TraceWriter writer(trace_, {"phi_1", "phi_2", "phi_3"}, comments);
    ControlVector phi = ControlVector::Zero(3);
    for (int row = 0; row < 200; ++row) {
      const double t_s = 5e-7 * row;
      const double a = 1e5 * t_s;
      const StokesVector s_in(std::cos(a), std::sin(a), 0.0);
      const StokesVector s_out = t_s < 4e-5 ? s_in : StokesVector(0.0, 0.6, 0.8);
      phi[0] = 0.1 * std::sin(a);
      writer.Write(t_s, s_in, s_out, 0.0, phi);
    }
  }

  static bool IsPng(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::array<char, 8> signature{};
    in.read(signature.data(), signature.size());
    return in.gcount() == 8 && std::string(signature.data() + 1, 3) == "PNG";
  }

  std::string PathIn(const std::string& name) const { return (directory_ / name).string(); }

  fs::path directory_;
  CLI::App app_{"dpc"};
  CLI::App* command_ = nullptr;
  PlotOptions options_;
  std::string trace_, png_, out_, err_;
};

TEST_F(PlotCommandTest, ParsesEveryOption) {
  WriteTrace(true);
  Parse({trace_, "-o", png_, "--title", "my title"});
  EXPECT_TRUE(command_->parsed());
  EXPECT_EQ(command_->get_name(), "plot");
  EXPECT_EQ(options_.trace_path, trace_);
  EXPECT_EQ(options_.output_path, png_);
  EXPECT_EQ(options_.title, "my title");
}

TEST_F(PlotCommandTest, OutputHasALongName) {
  WriteTrace(true);
  Parse({trace_, "--output", png_});
  EXPECT_EQ(options_.output_path, png_);
  EXPECT_TRUE(options_.title.empty());
}

TEST_F(PlotCommandTest, OutputIsRequired) {
  WriteTrace(true);
  EXPECT_THROW(Parse({trace_}), CLI::RequiredError);
}

TEST_F(PlotCommandTest, TraceIsRequired) {
  EXPECT_THROW(Parse({"-o", png_}), CLI::RequiredError);
}

TEST_F(PlotCommandTest, TraceMustExist) {
  EXPECT_THROW(Parse({PathIn("missing.csv"), "-o", png_}), CLI::ValidationError);
}

TEST_F(PlotCommandTest, DrawsTheFigure) {
  WriteTrace(true);
  Parse({trace_, "-o", png_});
  ASSERT_EQ(Run(), cli::ExitCode::kOk) << err_;
  EXPECT_TRUE(IsPng(png_));
  EXPECT_EQ(out_, "figure " + png_ + "\n");
  EXPECT_TRUE(err_.empty()) << err_;
}

TEST_F(PlotCommandTest, DrawsTheFigureWithAGivenTitle) {
  WriteTrace(true);
  Parse({trace_, "-o", png_, "--title", "another title"});
  ASSERT_EQ(Run(), cli::ExitCode::kOk) << err_;
  EXPECT_TRUE(IsPng(png_));
}

TEST_F(PlotCommandTest, AMissingTraceIsARuntimeError) {
  options_.trace_path = PathIn("missing.csv");  // past the command line's existence check
  options_.output_path = png_;
  EXPECT_EQ(Run(), cli::ExitCode::kRuntimeError);
  EXPECT_NE(err_.find("dpc plot: "), std::string::npos) << err_;
  EXPECT_NE(err_.find("missing.csv"), std::string::npos) << err_;
  EXPECT_FALSE(fs::exists(png_));
}

TEST_F(PlotCommandTest, ATraceNotWrittenByDpcSimIsARuntimeError) {
  WriteTrace(false);
  Parse({trace_, "-o", png_});
  EXPECT_EQ(Run(), cli::ExitCode::kRuntimeError);
  EXPECT_NE(err_.find("not a dpc trace"), std::string::npos) << err_;
  EXPECT_FALSE(fs::exists(png_));
}

TEST_F(PlotCommandTest, AnUnwritableOutputIsARuntimeError) {
  WriteTrace(true);
  Parse({trace_, "-o", PathIn("missing_directory/figure.png")});
  EXPECT_EQ(Run(), cli::ExitCode::kRuntimeError);
  EXPECT_NE(err_.find("missing_directory"), std::string::npos) << err_;
  EXPECT_TRUE(out_.empty()) << out_;
}

}  // namespace
}  // namespace dpc::tools
