#include "trace_envelope.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "dpc/sim/trace_writer.h"

namespace dpc {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

ControlVector Controls(double a, double b) {
  ControlVector phi(2);
  phi << a, b;
  return phi;
}

class TraceEnvelopeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("dpc_trace_envelope_test_" + std::to_string(::getpid()) + "_" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(directory_);
    path_ = (directory_ / "trace.csv").string();
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  void WriteText(const std::string& text) { std::ofstream(path_) << text; }

  std::string ErrorOf(int bucket_count) {
    try {
      ReadTraceEnvelope(path_, bucket_count);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }

  std::filesystem::path directory_;
  std::string path_;
};

TEST_F(TraceEnvelopeTest, ReadsCommentsHeaderAndControlNames) {
  { TraceWriter writer(path_, {"phi_1", "v_2"}, {"scenario: fig3", "seed 5"}); }
  const TraceHeader header = ReadTraceHeader(path_);
  EXPECT_EQ(header.comment_lines, (std::vector<std::string>{"scenario: fig3", "seed 5"}));
  EXPECT_EQ(header.control_names, (std::vector<std::string>{"phi_1", "v_2"}));
  ASSERT_EQ(header.columns.size(), static_cast<size_t>(kTraceFixedColumnCount + 2));
  EXPECT_EQ(header.columns[0], "t_s");
  EXPECT_EQ(header.columns[7], "error_deg");
  EXPECT_EQ(header.header_line, 3);
}

TEST_F(TraceEnvelopeTest, KeepsEveryRowWhenBucketsOutnumberRows) {
  {
    TraceWriter writer(path_, {"phi_1", "phi_2"}, {});
    for (int row = 0; row < 50; ++row) {
      writer.Write(row * 1e-3, StokesVector::UnitX(), StokesVector(0, 0.6, 0.8), row * 0.5,
                   Controls(std::sin(row), -row));
    }
  }
  const TraceEnvelope envelope = ReadTraceEnvelope(path_, 1000);
  EXPECT_EQ(envelope.rows, 50);
  EXPECT_EQ(envelope.t_min_s, 0.0);
  EXPECT_DOUBLE_EQ(envelope.t_max_s, 49e-3);
  const int phi_1 = envelope.ColumnIndex("phi_1");
  const int phi_2 = envelope.ColumnIndex("phi_2");
  ASSERT_EQ(phi_1, kTraceFixedColumnCount - 1);
  ASSERT_EQ(envelope.points[static_cast<size_t>(phi_1)].size(), 50u);
  for (int row = 0; row < 50; ++row) {
    const EnvelopePoint& point = envelope.points[static_cast<size_t>(phi_1)][row];
    EXPECT_NEAR(point.t_s, row * 1e-3, 1e-15);
    EXPECT_NEAR(point.value, std::sin(row), 5e-9);
  }
  EXPECT_EQ(envelope.min_value[static_cast<size_t>(phi_2)], -49.0);
  EXPECT_EQ(envelope.max_value[static_cast<size_t>(phi_2)], 0.0);
  EXPECT_EQ(envelope.ColumnIndex("s_out_2"), 4);
  EXPECT_EQ(envelope.ColumnIndex("t_s"), -1);
  EXPECT_EQ(envelope.ColumnIndex("nope"), -1);
}

TEST_F(TraceEnvelopeTest, KeepsFirstLastMinAndMaxOfEveryBucket) {
  constexpr int kRows = 20'000;
  constexpr int kBuckets = 37;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> t(kRows);
  std::vector<double> value(kRows);
  {
    TraceWriter writer(path_, {"phi_1", "phi_2"}, {});
    for (int row = 0; row < kRows; ++row) {
      t[row] = row * 2e-8;
      value[row] = row == 12345 ? 40.0 : normal(rng);  // one outlier
      writer.Write(t[row], StokesVector::UnitX(), StokesVector::UnitX(), 0.0,
                   Controls(value[row], 0.0));
    }
  }
  const TraceEnvelope envelope = ReadTraceEnvelope(path_, kBuckets);
  const std::vector<EnvelopePoint>& kept =
      envelope.points[static_cast<size_t>(envelope.ColumnIndex("phi_1"))];

  // The values re-read from the file (9 significant digits), bucket by bucket, by brute force.
  const auto parsed = [](double x) { return std::stod(fmt::format("{:.9g}", x)); };
  const double t_max = parsed(t.back());
  std::map<int, std::vector<int>> rows_of_bucket;
  for (int row = 0; row < kRows; ++row) {
    const int bucket =
        std::min(kBuckets - 1, static_cast<int>(parsed(t[row]) * (kBuckets / t_max)));
    rows_of_bucket[bucket].push_back(row);
  }
  std::vector<EnvelopePoint> expected;
  for (const auto& [bucket, rows] : rows_of_bucket) {
    const auto by_value = [&](int a, int b) { return parsed(value[a]) < parsed(value[b]); };
    std::set<int> keep = {rows.front(), rows.back(),
                          *std::min_element(rows.begin(), rows.end(), by_value),
                          *std::max_element(rows.begin(), rows.end(), by_value)};
    for (int row : keep) expected.push_back({parsed(t[row]), parsed(value[row])});
  }
  ASSERT_EQ(kept.size(), expected.size());
  EXPECT_LE(kept.size(), 4u * kBuckets);
  for (size_t i = 0; i < kept.size(); ++i) {
    EXPECT_EQ(kept[i].t_s, expected[i].t_s) << i;
    EXPECT_EQ(kept[i].value, expected[i].value) << i;
  }
  EXPECT_EQ(envelope.max_value[static_cast<size_t>(envelope.ColumnIndex("phi_1"))], 40.0);
  EXPECT_TRUE(std::any_of(kept.begin(), kept.end(),
                          [](const EnvelopePoint& p) { return p.value == 40.0; }));
}

TEST_F(TraceEnvelopeTest, SkipsNonFiniteValuesAndTimes) {
  {
    TraceWriter writer(path_, {"phi_1", "phi_2"}, {});
    writer.Write(0.0, StokesVector::UnitX(), StokesVector::UnitX(), 0.0, Controls(kNaN, 1.0));
    writer.Write(1.0, StokesVector::UnitX(), StokesVector::UnitX(), 0.0,
                 Controls(std::numeric_limits<double>::infinity(), 2.0));
    writer.Write(kNaN, StokesVector::UnitX(), StokesVector::UnitX(), 0.0, Controls(5.0, 3.0));
  }
  const TraceEnvelope envelope = ReadTraceEnvelope(path_, 10);
  EXPECT_EQ(envelope.rows, 3);
  EXPECT_EQ(envelope.t_max_s, 1.0);
  const size_t phi_1 = static_cast<size_t>(envelope.ColumnIndex("phi_1"));
  const size_t phi_2 = static_cast<size_t>(envelope.ColumnIndex("phi_2"));
  EXPECT_TRUE(envelope.points[phi_1].empty());
  EXPECT_TRUE(std::isnan(envelope.min_value[phi_1]));
  EXPECT_EQ(envelope.points[phi_2].size(), 2u);
  EXPECT_EQ(envelope.max_value[phi_2], 2.0);
}

TEST_F(TraceEnvelopeTest, TraceWithoutRowsHasNoTimeRange) {
  { TraceWriter writer(path_, {"phi_1"}, {"only a header"}); }
  const TraceEnvelope envelope = ReadTraceEnvelope(path_, 10);
  EXPECT_EQ(envelope.rows, 0);
  EXPECT_TRUE(std::isnan(envelope.t_min_s));
  EXPECT_TRUE(envelope.points[0].empty());
}

TEST_F(TraceEnvelopeTest, ReportsAMalformedRowWithItsLineNumber) {
  WriteText(std::string("# c\n") + std::string(kTraceFixedHeader) + ",phi_1\n" +
            "0,1,0,0,1,0,0,0,0.5\n" + "1,1,0,0,1,0,0,0\n");
  EXPECT_NE(ErrorOf(10).find(":4: expected 9 fields"), std::string::npos) << ErrorOf(10);
  WriteText(std::string(kTraceFixedHeader) + ",phi_1\n" + "0,1,0,0,1,0,0,0,abc\n");
  EXPECT_NE(ErrorOf(10).find(":2: field 9 \"abc\" is not a number"), std::string::npos)
      << ErrorOf(10);
  WriteText(std::string(kTraceFixedHeader) + "\n" + "0,1,0,0,1,0,0,0,7\n");
  EXPECT_NE(ErrorOf(10).find("expected 8 fields"), std::string::npos) << ErrorOf(10);
}

TEST_F(TraceEnvelopeTest, RejectsAFileThatIsNotATrace) {
  WriteText("# comment\ntime,x,y\n1,2,3\n");
  EXPECT_THROW(ReadTraceHeader(path_), std::runtime_error);
  WriteText(std::string(kTraceFixedHeader) + "_extra\n");
  EXPECT_THROW(ReadTraceHeader(path_), std::runtime_error);
  WriteText("# comments only\n");
  EXPECT_THROW(ReadTraceHeader(path_), std::runtime_error);
}

TEST_F(TraceEnvelopeTest, MissingFileThrowsNamingIt) {
  const std::string missing = (directory_ / "missing.csv").string();
  try {
    ReadTraceHeader(missing);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadTraceEnvelope(missing, 10), std::runtime_error);
}

TEST_F(TraceEnvelopeTest, RejectsABadBucketCount) {
  { TraceWriter writer(path_, {}, {}); }
  EXPECT_THROW(ReadTraceEnvelope(path_, 0), std::invalid_argument);
  EXPECT_THROW(ReadTraceEnvelope(path_, kMaxEnvelopeBuckets + 1), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
