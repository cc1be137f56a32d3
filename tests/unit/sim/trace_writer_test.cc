#include "dpc/sim/trace_writer.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace dpc {
namespace {

std::vector<std::string> ReadLines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<double> ParseRow(const std::string& line) {
  std::vector<double> values;
  std::stringstream stream(line);
  for (std::string field; std::getline(stream, field, ',');) values.push_back(std::stod(field));
  return values;
}

ControlVector Controls(std::initializer_list<double> values) {
  ControlVector phi(static_cast<Eigen::Index>(values.size()));
  Eigen::Index i = 0;
  for (double v : values) phi[i++] = v;
  return phi;
}

class TraceWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("dpc_trace_writer_test_" + std::to_string(::getpid()) + "_" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(directory_);
    path_ = (directory_ / "trace.csv").string();
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  std::filesystem::path directory_;
  std::string path_;
};

TEST_F(TraceWriterTest, WritesCommentsThenHeader) {
  {
    TraceWriter writer(path_, {"phi_1", "phi_2", "phi_3"}, {"scenario: fig3", "seed = 7"});
    EXPECT_EQ(writer.path(), path_);
    EXPECT_EQ(writer.rows(), 0);
  }
  const std::vector<std::string> lines = ReadLines(path_);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0], "# scenario: fig3");
  EXPECT_EQ(lines[1], "# seed = 7");
  EXPECT_EQ(lines[2],
            "t_s,s_in_1,s_in_2,s_in_3,s_out_1,s_out_2,s_out_3,error_deg,phi_1,phi_2,phi_3");
}

TEST(TraceWriterHeaderTest, FixedColumnCountMatchesTheFixedHeader) {
  const auto commas = std::count(kTraceFixedHeader.begin(), kTraceFixedHeader.end(), ',');
  EXPECT_EQ(commas + 1, kTraceFixedColumnCount);
}

TEST_F(TraceWriterTest, NoControlsAndNoComments) {
  { TraceWriter writer(path_, {}, {}); }
  const std::vector<std::string> lines = ReadLines(path_);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0], "t_s,s_in_1,s_in_2,s_in_3,s_out_1,s_out_2,s_out_3,error_deg");
}

TEST_F(TraceWriterTest, RowsParseBackToTheWrittenValues) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> exponent(-12.0, 12.0);
  std::vector<std::vector<double>> written;
  {
    TraceWriter writer(path_, {"a", "b", "c", "d"}, {"round trip"});
    for (int row = 0; row < 1000; ++row) {
      const double t_s = 1e-3 + row * 2e-8 + row * 1.234567e-14;  // 12 significant digits
      const StokesVector s_in = StokesVector(unit(rng), unit(rng), unit(rng)).normalized();
      const StokesVector s_out = StokesVector(unit(rng), unit(rng), unit(rng)).normalized();
      const double error_deg = std::pow(10.0, exponent(rng));
      const ControlVector phi =
          Controls({unit(rng), -std::pow(10.0, exponent(rng)), 0.0, 1.0 / 3.0});
      writer.Write(t_s, s_in, s_out, error_deg, phi);
      written.push_back({t_s, s_in.x(), s_in.y(), s_in.z(), s_out.x(), s_out.y(), s_out.z(),
                         error_deg, phi[0], phi[1], phi[2], phi[3]});
    }
    EXPECT_EQ(writer.rows(), 1000);
    writer.Flush();
  }
  const std::vector<std::string> lines = ReadLines(path_);
  ASSERT_EQ(lines.size(), 2u + written.size());
  for (size_t row = 0; row < written.size(); ++row) {
    const std::vector<double> values = ParseRow(lines[row + 2]);
    ASSERT_EQ(values.size(), written[row].size()) << lines[row + 2];
    // {:.12g} → ≤ 5e-12 relative for t_s; {:.9g} → ≤ 5e-9 relative for the rest.
    EXPECT_NEAR(values[0], written[row][0], 5e-12 * std::abs(written[row][0]));
    for (size_t column = 1; column < values.size(); ++column) {
      EXPECT_NEAR(values[column], written[row][column], 5e-9 * std::abs(written[row][column]))
          << "row " << row << " column " << column;
    }
  }
}

TEST_F(TraceWriterTest, NonFiniteValuesAreWrittenAsInfAndNaN) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  {
    TraceWriter writer(path_, {"phi_1"}, {});
    writer.Write(0.5, StokesVector::UnitX(), StokesVector::UnitY(), kInf,
                 Controls({std::numeric_limits<double>::quiet_NaN()}));
  }
  const std::vector<std::string> lines = ReadLines(path_);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[1], "0.5,1,0,0,0,1,0,inf,nan");
}

TEST_F(TraceWriterTest, HundredThousandRowsAreWrittenAndCounted) {
  constexpr int kRows = 100'000;  // ~9 MB: the buffer is drained several times
  {
    TraceWriter writer(path_, {"phi_1", "phi_2", "phi_3", "phi_4"}, {"one", "two"});
    const ControlVector phi = Controls({0.125, -0.25, 0.5, -1.0});
    for (int row = 0; row < kRows; ++row) {
      writer.Write(row * 2e-8, StokesVector::UnitX(), StokesVector::UnitZ(), 0.1 * row, phi);
    }
    EXPECT_EQ(writer.rows(), kRows);
  }
  const std::vector<std::string> lines = ReadLines(path_);
  ASSERT_EQ(lines.size(), 3u + kRows);
  EXPECT_EQ(lines[3], "0,1,0,0,0,0,1,0,0.125,-0.25,0.5,-1");
  const std::vector<double> last = ParseRow(lines.back());
  EXPECT_NEAR(last[0], (kRows - 1) * 2e-8, 1e-18);
  EXPECT_NEAR(last[7], 0.1 * (kRows - 1), 1e-6);
}

TEST_F(TraceWriterTest, RejectsBadControlNames) {
  for (const char* bad : {"", "a,b", "a\"b", "a'b", "a b", "a\tb", "a\nb", "a\rb"}) {
    EXPECT_THROW(TraceWriter(path_, {"phi_1", bad}, {}), std::invalid_argument)
        << "name '" << bad << "'";
  }
  EXPECT_FALSE(std::filesystem::exists(path_)) << "validation happens before the file opens";
}

TEST_F(TraceWriterTest, RejectsDuplicateControlNames) {
  EXPECT_THROW(TraceWriter(path_, {"phi_1", "phi_2", "phi_1"}, {}), std::invalid_argument);
}

TEST_F(TraceWriterTest, RejectsTooManyControlNames) {
  std::vector<std::string> names;
  for (int i = 0; i <= kMaxControls; ++i) names.push_back("phi_" + std::to_string(i + 1));
  EXPECT_THROW(TraceWriter(path_, names, {}), std::invalid_argument);
}

TEST_F(TraceWriterTest, RejectsCommentLinesWithLineBreaks) {
  EXPECT_THROW(TraceWriter(path_, {}, {"two\nlines"}), std::invalid_argument);
}

TEST_F(TraceWriterTest, UnwritablePathThrowsNamingThePathAndTheReason) {
  const std::string bad_path = (directory_ / "missing_directory" / "trace.csv").string();
  try {
    TraceWriter writer(bad_path, {"phi_1"}, {});
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(bad_path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file or directory"), std::string::npos)
        << e.what();
  }
}

TEST_F(TraceWriterTest, ControlCountMismatchThrows) {
  TraceWriter writer(path_, {"phi_1", "phi_2", "phi_3"}, {});
  EXPECT_THROW(writer.Write(0.0, StokesVector::UnitX(), StokesVector::UnitX(), 0.0,
                            Controls({1.0, 2.0})),
               std::invalid_argument);
  EXPECT_THROW(writer.Write(0.0, StokesVector::UnitX(), StokesVector::UnitX(), 0.0,
                            Controls({1.0, 2.0, 3.0, 4.0})),
               std::invalid_argument);
  EXPECT_EQ(writer.rows(), 0);
}

TEST_F(TraceWriterTest, FlushReportsAFullDisk) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  TraceWriter writer("/dev/full", {"phi_1"}, {});
  writer.Write(0.0, StokesVector::UnitX(), StokesVector::UnitX(), 0.0, Controls({1.0}));
  EXPECT_THROW(writer.Flush(), std::runtime_error);
}  // the destructor must not throw after the failure

TEST_F(TraceWriterTest, FlushMakesRowsVisibleWhileOpen) {
  TraceWriter writer(path_, {"phi_1"}, {});
  writer.Write(1.0, StokesVector::UnitX(), StokesVector::UnitX(), 0.0, Controls({2.0}));
  writer.Flush();
  const std::vector<std::string> lines = ReadLines(path_);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[1], "1,1,0,0,1,0,0,0,2");
}

}  // namespace
}  // namespace dpc
