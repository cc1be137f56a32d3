#include "paper_figure.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "dpc/sim/trace_writer.h"
#include "support/png_pixels.h"

namespace dpc {
namespace {

struct PngSize {
  uint32_t width_px = 0;
  uint32_t height_px = 0;
};

// Checks the PNG signature and reads the size from the IHDR chunk (bytes 16–23, big-endian).
PngSize ReadPngSize(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::array<unsigned char, 24> head{};
  in.read(reinterpret_cast<char*>(head.data()), head.size());
  if (in.gcount() != static_cast<std::streamsize>(head.size())) return {};
  constexpr std::array<unsigned char, 8> kSignature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A,
                                                       '\n'};
  if (!std::equal(kSignature.begin(), kSignature.end(), head.begin())) return {};
  if (std::string(head.begin() + 12, head.begin() + 16) != "IHDR") return {};
  const auto be32 = [&](int at) {
    return (uint32_t{head[at]} << 24) | (uint32_t{head[at + 1]} << 16) |
           (uint32_t{head[at + 2]} << 8) | uint32_t{head[at + 3]};
  };
  return {be32(16), be32(20)};
}

// A paper-like closed-loop trace: the input SOP rotates about S3 at `rate_rad_per_s`,
// perturbed about S2; S_out follows it until `activation_s`, then locks onto `target` while
// the controls wander.
void WriteSyntheticTrace(const std::string& path, int control_count, int rows,
                         double duration_s, double activation_s, const StokesVector& target) {
  std::vector<std::string> names;
  for (int i = 0; i < control_count; ++i) names.push_back("phi_" + std::to_string(i + 1));
  TraceWriter writer(path, names, {"synthetic trace for paper_figure_test", "seed 42"});
  std::mt19937_64 rng(42);
  std::normal_distribution<double> noise(0.0, 1.0);
  ControlVector phi = ControlVector::Zero(control_count);
  const double rate_rad_per_s = 2e4;
  for (int row = 0; row < rows; ++row) {
    const double t_s = duration_s * row / rows;
    const double a = rate_rad_per_s * t_s;
    const double b = 0.3 * std::sin(3e3 * t_s) + 0.05 * noise(rng);
    const StokesVector s_in(std::cos(a) * std::cos(b), std::sin(a) * std::cos(b), std::sin(b));
    StokesVector s_out = s_in;
    if (t_s >= activation_s) {
      const double w = std::exp(-(t_s - activation_s) / 5e-5);
      s_out = (w * s_in + (1.0 - w) * target +
               0.01 * StokesVector(noise(rng), noise(rng), noise(rng)))
                  .normalized();
      for (int i = 0; i < control_count; ++i) phi[i] += 0.02 * noise(rng);
    }
    const double error_deg = std::acos(std::clamp(s_out.dot(target), -1.0, 1.0)) * 180.0 / M_PI;
    writer.Write(t_s, s_in, s_out, error_deg, phi);
  }
}

class PaperFigureTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("dpc_paper_figure_test_" + std::to_string(::getpid()) + "_" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(directory_);
    trace_ = (directory_ / "trace.csv").string();
    png_ = (directory_ / "figure.png").string();
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  std::filesystem::path directory_;
  std::string trace_;
  std::string png_;
  const StokesVector target_ = StokesVector(0.0, 0.6, 0.8);
};

TEST_F(PaperFigureTest, ThreeControlFigureHasTheDocumentedSize) {
  WriteSyntheticTrace(trace_, 3, 4000, 10e-3, 2e-3, target_);
  FigureOptions options;
  options.title = "3-stage DPC, M = R1 R3 R1, gradient projection";
  options.activation_s = 2e-3;
  options.target_point = target_;
  WritePaperFigure(trace_, png_, options);
  const PngSize size = ReadPngSize(png_);
  EXPECT_EQ(size.width_px, 1000u);
  EXPECT_EQ(size.height_px, static_cast<uint32_t>(PaperFigureHeightPx(3, options)));
  EXPECT_EQ(PaperFigureHeightPx(3, options), kFigureTitleBandPx + 5 * 170 + kFigureAxisBandPx);
}

// Panel p's rows in a figure with a title (p = 0: S_out, 1: error, 2…: the controls).
std::pair<uint32_t, uint32_t> PanelRows(int panel, const FigureOptions& options) {
  const int top = (options.title.empty() ? kFigureNoTitleBandPx : kFigureTitleBandPx) +
                  panel * options.panel_height_px;
  return {static_cast<uint32_t>(top), static_cast<uint32_t>(top + options.panel_height_px)};
}

TEST_F(PaperFigureTest, PanelBShowsTheErrorCurveWithTheExtinctionScale) {
  WriteSyntheticTrace(trace_, 3, 4000, 10e-3, 2e-3, target_);
  FigureOptions options;
  options.title = "error panel";
  options.activation_s = 2e-3;
  options.target_point = target_;
  WritePaperFigure(trace_, png_, options);
  const testing::PngPixels png = testing::ReadPngPixels(png_);
  const auto error_colour = testing::HexColour("#B2182B");
  const auto [b0, b1] = PanelRows(1, options);
  const auto [a0, a1] = PanelRows(0, options);
  const auto [c0, c1] = PanelRows(2, options);
  // The error curve runs across panel (b) (from ~90° before the DPC to well below 1° after).
  EXPECT_GT(png.CountNear(b0, b1, error_colour), 400u);
  EXPECT_EQ(png.CountNear(a0, a1, error_colour, 20), 0u);
  EXPECT_EQ(png.CountNear(c0, c1, error_colour, 20), 0u);
}

TEST_F(PaperFigureTest, ControlRangesAreGuideLinesWhenNearAndNamedWhenFar) {
  WriteSyntheticTrace(trace_, 3, 4000, 10e-3, 2e-3, target_);
  FigureOptions options;
  options.title = "ranges";
  const auto range_colour = testing::HexColour("#8C6D1F");
  const auto count_in = [&](int panel) {
    const testing::PngPixels png = testing::ReadPngPixels(png_);
    const auto [y0, y1] = PanelRows(panel, options);
    return png.CountNear(y0, y1, range_colour, 25);
  };
  WritePaperFigure(trace_, png_, options);
  EXPECT_EQ(count_in(2), 0u) << "no ranges given: no guide lines";
  // |φ| ≲ 1 in the synthetic trace: ±1.5 is near, two dashed lines across the panel.
  options.control_ranges = {{-1.5, 1.5}, {-1.5, 1.5}, {-1.5, 1.5}};
  WritePaperFigure(trace_, png_, options);
  const size_t near = count_in(2);
  EXPECT_GT(near, 300u);  // two dashed lines ~800 px wide (~430 px seen)
  EXPECT_GT(count_in(4), 300u);
  EXPECT_LT(count_in(1), 10u) << "not in the error panel";
  // ±100 is far: not drawn (the signal keeps its scale), only named in the panel.
  options.control_ranges = {{-100, 100}, {-100, 100}, {-100, 100}};
  WritePaperFigure(trace_, png_, options);
  const size_t far = count_in(2);
  EXPECT_GT(far, 0u) << "the range is named";
  EXPECT_LT(far, near / 3);
  // One range per control, min <= max.
  options.control_ranges = {{-1, 1}};
  EXPECT_THROW(WritePaperFigure(trace_, png_, options), std::invalid_argument);
  options.control_ranges = {{1, -1}, {-1, 1}, {-1, 1}};
  EXPECT_THROW(WritePaperFigure(trace_, png_, options), std::invalid_argument);
}

TEST_F(PaperFigureTest, FourControlFigureWithoutTitleOrMarkers) {
  WriteSyntheticTrace(trace_, 4, 4000, 10e-3, 2e-3, target_);
  FigureOptions options;
  options.width_px = 800;
  options.panel_height_px = 120;
  options.time_scale = 1e6;
  options.time_unit = "µs";
  WritePaperFigure(trace_, png_, options);
  const PngSize size = ReadPngSize(png_);
  EXPECT_EQ(size.width_px, 800u);
  EXPECT_EQ(size.height_px, static_cast<uint32_t>(kFigureNoTitleBandPx + 6 * 120 +
                                                  kFigureAxisBandPx));
}

TEST_F(PaperFigureTest, LargeTraceIsDrawnFromItsEnvelope) {
  // 300 k rows (~40 MB): drawn directly, gnuplot would need ~10 s; the envelope needs a second.
  WriteSyntheticTrace(trace_, 4, 300'000, 10e-3, 2e-3, target_);
  FigureOptions options;
  options.activation_s = 2e-3;
  options.target_point = target_;
  WritePaperFigure(trace_, png_, options);
  EXPECT_EQ(ReadPngSize(png_).height_px, static_cast<uint32_t>(PaperFigureHeightPx(4, options)));
}

TEST_F(PaperFigureTest, ArbitraryNamesQuotesAndDegenerateColumnsRender) {
  {
    TraceWriter writer(trace_, {"v_stage2", "phi_10", "all_nan"}, {});
    ControlVector phi(3);
    for (int row = 0; row < 10; ++row) {
      phi << 0.5, row, std::nan("");  // a constant, a ramp, and no finite value
      writer.Write(row * 1e-6, StokesVector::UnitX(), StokesVector::UnitZ(), 0.0, phi);
    }
  }
  FigureOptions options;
  options.title = "it's \"quoted\" & {braced} ^_@";
  options.activation_s = 1.0;  // after the trace's end: no line
  WritePaperFigure(trace_, png_, options);
  EXPECT_EQ(ReadPngSize(png_).height_px, static_cast<uint32_t>(PaperFigureHeightPx(3, options)));
}

TEST_F(PaperFigureTest, ExtremeValuesRender) {
  {
    TraceWriter writer(trace_, {"phi_1", "phi_2"}, {});
    ControlVector phi(2);
    for (int row = 0; row < 10; ++row) {
      const double sign = row % 2 == 0 ? 1.0 : -1.0;
      phi << sign * 1.7e308, 1e-300 * row;  // a range that overflows a double; a tiny one
      writer.Write(row * 1e-6, StokesVector::UnitX(), StokesVector::UnitZ(), 0.0, phi);
    }
  }
  WritePaperFigure(trace_, png_, FigureOptions{});
  EXPECT_EQ(ReadPngSize(png_).width_px, 1000u);
}

TEST_F(PaperFigureTest, SingleRowRenders) {
  {
    TraceWriter writer(trace_, {"phi_1"}, {});
    writer.Write(1e-3, StokesVector::UnitX(), StokesVector::UnitY(), 90.0, ControlVector::Zero(1));
  }
  WritePaperFigure(trace_, png_, FigureOptions{});
  EXPECT_EQ(ReadPngSize(png_).width_px, 1000u);
}

TEST_F(PaperFigureTest, MissingTraceThrows) {
  EXPECT_THROW(WritePaperFigure((directory_ / "missing.csv").string(), png_, FigureOptions{}),
               std::runtime_error);
  EXPECT_FALSE(std::filesystem::exists(png_));
}

TEST_F(PaperFigureTest, TraceWithoutRowsThrows) {
  { TraceWriter writer(trace_, {"phi_1"}, {}); }
  EXPECT_THROW(WritePaperFigure(trace_, png_, FigureOptions{}), std::runtime_error);
}

TEST_F(PaperFigureTest, PngInAMissingDirectoryThrows) {
  WriteSyntheticTrace(trace_, 3, 100, 1e-3, 0.5e-3, target_);
  const std::string png = (directory_ / "missing" / "f.png").string();
  EXPECT_THROW(WritePaperFigure(trace_, png, FigureOptions{}), std::runtime_error);
  EXPECT_THROW(WriteRatePlot(png, "", {{"a", {1.0}, {1.0}}}), std::runtime_error);
}

TEST_F(PaperFigureTest, RejectsBadOptions) {
  WriteSyntheticTrace(trace_, 3, 100, 1e-3, 0.5e-3, target_);
  FigureOptions narrow;
  narrow.width_px = kFigureMinWidthPx - 1;
  EXPECT_THROW(WritePaperFigure(trace_, png_, narrow), std::invalid_argument);
  FigureOptions flat;
  flat.panel_height_px = kFigureMinPanelHeightPx - 1;
  EXPECT_THROW(WritePaperFigure(trace_, png_, flat), std::invalid_argument);
  FigureOptions no_scale;
  no_scale.time_scale = 0.0;
  EXPECT_THROW(WritePaperFigure(trace_, png_, no_scale), std::invalid_argument);
  FigureOptions bad_activation;
  bad_activation.activation_s = std::nan("");
  EXPECT_THROW(WritePaperFigure(trace_, png_, bad_activation), std::invalid_argument);
  FigureOptions bad_target;
  bad_target.target_point = StokesVector(0.0, std::nan(""), 1.0);
  EXPECT_THROW(WritePaperFigure(trace_, png_, bad_target), std::invalid_argument);
  FigureOptions long_target;
  long_target.target_point = StokesVector(0.0, 1.2, 0.0);
  EXPECT_THROW(WritePaperFigure(trace_, png_, long_target), std::invalid_argument);
}

TEST_F(PaperFigureTest, RatePlotRenders) {
  std::vector<RateSeries> series = {
      {"gp, 3 stages", {1e3, 1e4, 1e5, 1e6}, {0.01, 0.1, 1.2, 15.0}},
      {"gpt, 4 stages", {1e3, 1e4, 1e5, 1e6}, {0.005, 0.04, 0.5, 0.0}},  // 0: left out
      {"it's dither", {1e3, 1e4}, {2.0, 30.0}},
  };
  WriteRatePlot(png_, "Mean error vs input SOP rate", series);
  const PngSize size = ReadPngSize(png_);
  EXPECT_EQ(size.width_px, static_cast<uint32_t>(kRatePlotWidthPx));
  EXPECT_EQ(size.height_px, static_cast<uint32_t>(kRatePlotHeightPx));
}

TEST(RatePlotLabels, SaysWhenACurveLiesOnAnother) {
  const std::vector<double> rates = {1e3, 1e4, 1e5};
  const std::vector<RateSeries> series = {
      {"pinv", rates, {0.1, 1.0, 10.0}},
      {"damped", rates, {0.1004, 0.998, 10.02}},  // within 1 %: hidden under pinv
      {"transpose", rates, {0.2, 2.0, 20.0}},
      {"gp", {1e3, 1e4}, {0.1, 1.0}},              // other rates: not compared
  };
  const std::vector<std::string> labels = RatePlotLabels(series);
  ASSERT_EQ(labels.size(), 4u);
  EXPECT_EQ(labels[0], "pinv");
  EXPECT_EQ(labels[1], "damped (coincides with pinv)");
  EXPECT_EQ(labels[2], "transpose");
  EXPECT_EQ(labels[3], "gp");
}

TEST_F(PaperFigureTest, RatePlotRejectsBadSeries) {
  EXPECT_THROW(WriteRatePlot(png_, "", {}), std::invalid_argument);
  EXPECT_THROW(WriteRatePlot(png_, "", {{"a", {1.0, 2.0}, {1.0}}}), std::invalid_argument);
  EXPECT_THROW(WriteRatePlot(png_, "", {{"a", {0.0, -1.0}, {1.0, 1.0}}}), std::invalid_argument);
}

}  // namespace
}  // namespace dpc
