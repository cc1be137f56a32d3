#include "paper_figure.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <regex>
#include <stdexcept>

#include "gnuplot_runner.h"
#include "dpc/sim/trace_writer.h"
#include "trace_envelope.h"

namespace dpc {
namespace {

// Pixels between a panel's edge and its plot area (twice this between two plot areas).
constexpr int kPanelGapPx = 6;
// A y-axis tick label needs about this much height to stay readable.
constexpr int kYTickSpacingPx = 35;
// Colours: Okabe–Ito, distinguishable with the common colour-vision deficiencies.
constexpr std::array<const char*, 3> kStokesColours = {"#0072B2", "#D55E00", "#009E73"};
constexpr const char* kControlColour = "#1F3F7A";
constexpr const char* kErrorColour = "#B2182B";
constexpr const char* kRangeColour = "#8C6D1F";
constexpr const char* kTargetColour = "#222222";
constexpr const char* kActivationColour = "#666666";
constexpr const char* kShadeColour = "#FBE3C9";
constexpr const char* kEventColour = "#7B3294";
constexpr std::array<const char*, 7> kSeriesColours = {"#0072B2", "#D55E00", "#009E73",
                                                      "#CC79A7", "#E69F00", "#56B4E9",
                                                      "#000000"};
constexpr std::array<int, 6> kSeriesPointTypes = {7, 5, 9, 11, 13, 15};

// The preamble shared by every figure: terminal, output, style.
void AppendPreamble(fmt::memory_buffer* script, const std::string& png_path, int width_px,
                    int height_px) {
  fmt::format_to(fmt::appender(*script),
                 "set terminal pngcairo size {},{} enhanced font 'DejaVu Sans,11' "
                 "linewidth 1.2 background rgb 'white'\n"
                 "set output {}\n"
                 "set encoding utf8\n"
                 "set border 15 lc rgb '#333333' lw 1\n"
                 "set tics nomirror out scale 0.6\n"
                 "set grid xtics ytics lc rgb '#DDDDDD' lw 1 dt 1\n",
                 width_px, height_px, GnuplotQuote(png_path));
}

// "(a)", "(b)", …, "(z)", "(aa)", …
std::string PanelLetter(int index) {
  std::string letters;
  for (int i = index; i >= 0; i = i / 26 - 1) letters.insert(letters.begin(), char('a' + i % 26));
  return "(" + letters + ")";
}

// The y label of a control column: "phi_3" / "phi3" → φ₃ (gnuplot enhanced text), anything
// else verbatim.
// The y label of control `index` (0-based): φ_i as the paper writes it, followed by the
// control's own name when it has one ("φ_1 wp1", "φ_4 wp2.orientation"), in gnuplot's enhanced
// text (the name's special characters escaped).
std::string ControlLabel(const std::string& name, int index) {
  static const std::regex kPhi("phi_?([0-9]+)");
  std::smatch match;
  std::string label = fmt::format("φ_{{{}}}", index + 1);
  if (std::regex_match(name, match, kPhi) && match[1].str() == std::to_string(index + 1)) {
    return fmt::format("{} enhanced", GnuplotQuote(label));
  }
  std::string escaped;
  for (const char c : name) {
    if (std::string_view("_^{}@&~\\").find(c) != std::string_view::npos) escaped += '\\';
    escaped += c;
  }
  return fmt::format("{} enhanced", GnuplotQuote(label + " " + escaped));
}

// The smallest of {1, 2, 5}·10^k at least `raw`.
double NiceStep(double raw) {
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double factor : {1.0, 2.0, 5.0}) {
    if (factor * decade >= raw * (1.0 - 1e-12)) return factor * decade;
  }
  return 10.0 * decade;
}

struct YAxis {
  double min;
  double max;
  double tick_step;
};

// A y range around the extremes [lo, hi] of a signal (8 % margins; ±max(10 %, 0.5) around a
// constant; [−1, 1] without finite values) and a {1, 2, 5}·10^k tick step giving at most about
// `intervals` intervals. Written so that no intermediate overflows, even for |lo|, |hi| near
// the largest double.
YAxis FitYAxis(double lo, double hi, int intervals) {
  constexpr double kLargest = std::numeric_limits<double>::max();
  double y_min = -1.0;
  double y_max = 1.0;
  if (std::isfinite(lo) && hi > lo) {
    const double pad = 0.08 * hi - 0.08 * lo;
    y_min = std::max(lo - pad, -kLargest);
    y_max = std::min(hi + pad, kLargest);
  } else if (std::isfinite(lo)) {
    const double pad = std::max(0.1 * std::abs(lo), 0.5);
    y_min = std::max(lo - pad, -kLargest);
    y_max = std::min(lo + pad, kLargest);
  }
  return {y_min, y_max, NiceStep(y_max / intervals - y_min / intervals)};
}

// The error panel's log axis: the error's extremes in whole decades (at least 1e-4°, at most
// 180°; two decades at least), and the extinction tics on the right axis: every 20 dB that
// falls inside, placed at the error it stands for (error = 2·atan(10^(dB/20))).
struct ErrorAxis {
  double min_deg;
  double max_deg;
  std::string extinction_tics;  ///< gnuplot's ("label" position, …) list
};

ErrorAxis FitErrorAxis(double lo_deg, double hi_deg) {
  constexpr double kFloorDeg = 1e-4;
  if (!std::isfinite(lo_deg) || !std::isfinite(hi_deg)) {
    lo_deg = 0.1;
    hi_deg = 100.0;
  }
  ErrorAxis axis;
  axis.min_deg = std::pow(10.0, std::floor(std::log10(std::max(lo_deg, kFloorDeg))));
  axis.max_deg = std::min(180.0, std::pow(10.0, std::ceil(std::log10(std::max(hi_deg, kFloorDeg)))));
  if (axis.max_deg < axis.min_deg * 100.0) axis.min_deg = axis.max_deg / 100.0;
  for (int db = 0; db >= -200; db -= 20) {
    const double error_deg = 2.0 * std::atan(std::pow(10.0, db / 20.0)) * 180.0 / M_PI;
    if (error_deg < axis.min_deg) break;
    if (error_deg > axis.max_deg) continue;
    fmt::format_to(std::back_inserter(axis.extinction_tics), "{}\"{}\" {:.6g}",
                   axis.extinction_tics.empty() ? "" : ", ", db, error_deg);
  }
  if (axis.extinction_tics.empty()) axis.extinction_tics = "\"\" 1";
  return axis;
}

// A datablock "$name" of (t · time_scale, value) pairs.
void AppendDatablock(fmt::memory_buffer* script, const std::string& name,
                     const std::vector<EnvelopePoint>& points, double time_scale) {
  auto out = fmt::appender(*script);
  fmt::format_to(out, "${} << EOD\n", name);
  for (const EnvelopePoint& point : points) {
    fmt::format_to(out, "{:.15g} {:.12g}\n", point.t_s * time_scale, point.value);
  }
  if (points.empty()) fmt::format_to(out, "NaN NaN\n");  // gnuplot refuses an empty block
  fmt::format_to(out, "EOD\n");
}

bool IsDrawableOnLogAxes(double x, double y) {
  return std::isfinite(x) && x > 0.0 && std::isfinite(y) && y > 0.0;
}

struct DecadeRange {
  double min;
  double max;
};

// A log-axis range for data in [lo, hi] (0 < lo ≤ hi): 5 % of the span (in decades) beyond
// the data on each side, so no marker sits on the frame; data spanning less than a decade get
// the enclosing whole decades instead, so that at least two major ticks are labelled.
DecadeRange FitDecades(double lo, double hi) {
  constexpr double kSlack = 1e-9;  // 1000 is 10^3, whatever log10 rounds it to
  const double lo_log = std::log10(lo);
  const double hi_log = std::log10(hi);
  if (hi_log - lo_log >= 1.0) {
    const double margin = 0.05 * (hi_log - lo_log);
    return {std::pow(10.0, lo_log - margin), std::pow(10.0, hi_log + margin)};
  }
  double lo_decade = std::floor(lo_log + kSlack);
  double hi_decade = std::ceil(hi_log - kSlack);
  if (hi_decade <= lo_decade) {
    lo_decade -= 1.0;
    hi_decade += 1.0;
  }
  return {std::pow(10.0, lo_decade), std::pow(10.0, hi_decade)};
}

void ValidateOptions(const FigureOptions& options) {
  if (options.width_px < kFigureMinWidthPx || options.width_px > 20000) {
    throw std::invalid_argument(fmt::format("figure width_px = {} must be in [{}, 20000]",
                                            options.width_px, kFigureMinWidthPx));
  }
  if (options.panel_height_px < kFigureMinPanelHeightPx || options.panel_height_px > 5000) {
    throw std::invalid_argument(fmt::format("figure panel_height_px = {} must be in [{}, 5000]",
                                            options.panel_height_px, kFigureMinPanelHeightPx));
  }
  if (!(std::isfinite(options.time_scale) && options.time_scale > 0.0)) {
    throw std::invalid_argument(
        fmt::format("figure time_scale = {} must be finite and positive", options.time_scale));
  }
  if (options.activation_s && !std::isfinite(*options.activation_s)) {
    throw std::invalid_argument("figure activation_s must be finite");
  }
  for (const auto& [from, to] : options.shaded_intervals) {
    if (!std::isfinite(from) || !std::isfinite(to) || !(from <= to)) {
      throw std::invalid_argument(fmt::format("figure shaded interval [{}, {}] must be finite with from <= to", from, to));
    }
  }
  for (const FigureEvent& event : options.events) {
    if (!std::isfinite(event.t_s)) throw std::invalid_argument("figure event time must be finite");
  }
  for (const auto& [lo, hi] : options.control_ranges) {
    if (std::isnan(lo) || std::isnan(hi) || !(lo <= hi)) {
      throw std::invalid_argument(fmt::format("figure control range [{}, {}] must have min <= max", lo, hi));
    }
  }
  if (options.target_point && !IsUnitStokes(*options.target_point)) {
    throw std::invalid_argument(fmt::format("figure target_point {} must be a unit Stokes vector",
                                            FormatStokes(*options.target_point)));
  }
}

// Fails early, with a clear message, where gnuplot would fail to open the output.
void RequireOutputDirectory(const std::string& png_path) {
  const std::filesystem::path directory = std::filesystem::path(png_path).parent_path();
  std::error_code error;
  if (!directory.empty() && !std::filesystem::is_directory(directory, error)) {
    throw std::runtime_error(fmt::format("cannot write '{}': directory '{}' does not exist",
                                         png_path, directory.string()));
  }
}

void RequireWrittenPng(const std::string& png_path) {
  std::error_code error;
  if (std::filesystem::file_size(png_path, error) == 0 || error) {
    throw std::runtime_error(fmt::format("gnuplot reported success but wrote no PNG '{}'",
                                         png_path));
  }
}

}  // namespace

int PaperFigureHeightPx(int control_count, const FigureOptions& options) {
  const int top_band_px = options.title.empty() ? kFigureNoTitleBandPx : kFigureTitleBandPx;
  return top_band_px + (2 + control_count) * options.panel_height_px + kFigureAxisBandPx;
}

void WritePaperFigure(const std::string& trace_csv, const std::string& png_path,
                      const FigureOptions& options) {
  ValidateOptions(options);
  RequireOutputDirectory(png_path);
  const int plot_width_px = options.width_px - kFigureLeftMarginPx - kFigureRightMarginPx;
  const TraceEnvelope envelope = ReadTraceEnvelope(trace_csv, plot_width_px);
  if (!std::isfinite(envelope.t_min_s)) {
    throw std::runtime_error(
        fmt::format("trace '{}' has no data row with a finite time t_s", trace_csv));
  }
  const std::vector<std::string>& controls = envelope.header.control_names;
  const int control_count = static_cast<int>(controls.size());
  if (!options.control_ranges.empty() && options.control_ranges.size() != controls.size()) {
    throw std::invalid_argument(fmt::format("figure: {} control ranges for a trace of {} controls",
                                            options.control_ranges.size(), controls.size()));
  }
  const int width_px = options.width_px;
  const int height_px = PaperFigureHeightPx(control_count, options);
  const int top_band_px = options.title.empty() ? kFigureNoTitleBandPx : kFigureTitleBandPx;
  const double w = width_px;
  const double h = height_px;

  fmt::memory_buffer script;
  auto out = fmt::appender(script);
  AppendPreamble(&script, png_path, width_px, height_px);

  // The data: s_out_1..3 and the controls, each reduced to its M4 envelope. Columns by position
  // (envelope index = column − 1), as the header fixes them.
  const size_t first_s_out = static_cast<size_t>(envelope.ColumnIndex("s_out_1"));
  const size_t first_control = kTraceFixedColumnCount - 1;
  for (size_t k = 0; k < 3; ++k) {
    AppendDatablock(&script, fmt::format("s_out_{}", k + 1), envelope.points[first_s_out + k],
                    options.time_scale);
  }
  const size_t error_column = static_cast<size_t>(envelope.ColumnIndex("error_deg"));
  AppendDatablock(&script, "error", envelope.points[error_column], options.time_scale);
  for (size_t i = 0; i < controls.size(); ++i) {
    AppendDatablock(&script, fmt::format("control_{}", i + 1),
                    envelope.points[first_control + i], options.time_scale);
  }
  // The activation line only when it falls on the time axis (gnuplot does not clip arrows).
  const bool draw_activation = options.activation_s &&
                               *options.activation_s >= envelope.t_min_s &&
                               *options.activation_s <= envelope.t_max_s;

  double x_min = envelope.t_min_s * options.time_scale;
  double x_max = envelope.t_max_s * options.time_scale;
  if (!(x_max > x_min)) {  // a single instant: give the axis some width
    x_min -= 0.5;
    x_max += 0.5;
  }
  fmt::format_to(out,
                 "set xrange [{:.15g}:{:.15g}]\n"
                 "set mxtics 2\n"
                 "set lmargin at screen {:.6f}\n"
                 "set rmargin at screen {:.6f}\n",
                 x_min, x_max, kFigureLeftMarginPx / w, 1.0 - kFigureRightMarginPx / w);
  if (draw_activation) {
    fmt::format_to(out,
                   "set arrow 10 from first {:.15g}, graph 0 to first {:.15g}, graph 1 nohead "
                   "dt (2,3) lc rgb '{}' lw 1.2 front\n",
                   *options.activation_s * options.time_scale,
                   *options.activation_s * options.time_scale, kActivationColour);
  }
  // Shaded intervals and events, in every panel, within the time axis only.
  size_t shaded = 0;
  for (const auto& [from, to] : options.shaded_intervals) {
    const double a = std::max(from, envelope.t_min_s), b = std::min(to, envelope.t_max_s);
    if (!(a <= b) || shaded >= kFigureMaxMarks) continue;
    ++shaded;
    fmt::format_to(out,
                   "set object {} rect from first {:.15g}, graph 0 to first {:.15g}, graph 1 behind "
                   "fc rgb '{}' fs solid 1.0 noborder\n",
                   shaded, a * options.time_scale, std::max(b * options.time_scale, a * options.time_scale), kShadeColour);
  }
  std::vector<const FigureEvent*> events;
  for (const FigureEvent& event : options.events) {
    if (event.t_s >= envelope.t_min_s && event.t_s <= envelope.t_max_s && events.size() < kFigureMaxMarks) {
      events.push_back(&event);
    }
  }
  for (size_t e = 0; e < events.size(); ++e) {
    fmt::format_to(out,
                   "set arrow {} from first {:.15g}, graph 0 to first {:.15g}, graph 1 nohead "
                   "dt (4,3) lc rgb '{}' lw 1.5 front\n",
                   100 + e, events[e]->t_s * options.time_scale, events[e]->t_s * options.time_scale, kEventColour);
  }
  if (options.title.empty()) {
    fmt::format_to(out, "set multiplot\n");
  } else {
    fmt::format_to(out, "set multiplot title {} noenhanced font ',13'\n",
                   GnuplotQuote(options.title));
  }

  // Panel geometry: panel p spans [top, top + panel_height_px) pixels from the top.
  const auto set_panel = [&](int panel) {
    const int top_px = top_band_px + panel * options.panel_height_px;
    fmt::format_to(out,
                   "set tmargin at screen {:.6f}\n"
                   "set bmargin at screen {:.6f}\n"
                   "set label 1 '{}' at screen {:.6f}, screen {:.6f} left font ',12'\n",
                   1.0 - (top_px + kPanelGapPx) / h,
                   1.0 - (top_px + options.panel_height_px - kPanelGapPx) / h,
                   PanelLetter(panel), 10.0 / w, 1.0 - (top_px + kPanelGapPx + 10) / h);
    if (panel == control_count + 1) {  // the bottom panel carries the time axis
      fmt::format_to(out, "set format x '%g'\nset xlabel {} noenhanced\n",
                     GnuplotQuote(fmt::format("Time ({})", options.time_unit)));
    } else {
      fmt::format_to(out, "set format x ''\nunset xlabel\n");
    }
  };

  // (a) S_out.
  set_panel(0);
  fmt::format_to(out,
                 "set yrange [-1.05:1.05]\n"
                 "set ytics -1, 0.5, 1\n"
                 "set mytics 2\n"
                 "set ylabel 'S_{{out}}' enhanced\n"
                 // Opaque: the key can reach into the plot (the right margin is the error
                 // panel's axis), and its samples must show over the data and the shading.
                 "set key outside right top vertical Left reverse samplen 2.5 spacing 1.15 opaque "
                 "box lc rgb '#CCCCCC'\n");
  if (options.target_point) {
    for (int k = 0; k < 3; ++k) {
      fmt::format_to(out,
                     "set arrow {} from graph 0, first {:.12g} to graph 1, first {:.12g} "
                     "nohead dt (6,4) lc rgb '{}' lw 1.2 front\n",
                     k + 1, (*options.target_point)[k], (*options.target_point)[k],
                     kTargetColour);
    }
  }
  if (events.size() <= kFigureMaxEventLabels) {
    for (size_t e = 0; e < events.size(); ++e) {
      fmt::format_to(out, "set label {} {} at first {:.15g}, graph 1.04 center noenhanced font ',8' tc rgb '{}'\n",
                     100 + e, GnuplotQuote(events[e]->label), events[e]->t_s * options.time_scale, kEventColour);
    }
  }
  fmt::format_to(out, "plot ");
  for (int k = 0; k < 3; ++k) {
    fmt::format_to(out, "{}$s_out_{} using 1:2 with lines lc rgb '{}' title 's_{}'",
                   k == 0 ? "" : ", \\\n     ", k + 1, kStokesColours[static_cast<size_t>(k)],
                   k + 1);
  }
  if (options.target_point) {
    fmt::format_to(out, ", \\\n     NaN with lines dt (6,4) lw 1.2 lc rgb '{}' title 'target'",
                   kTargetColour);
  }
  if (draw_activation) {
    fmt::format_to(out, ", \\\n     NaN with lines dt (2,3) lw 1.2 lc rgb '{}' title 'DPC on'",
                   kActivationColour);
  }
  if (shaded > 0) {
    fmt::format_to(out, ", \\\n     NaN with lines lw 8 lc rgb '{}' title {}", kShadeColour,
                   GnuplotQuote(options.shaded_label));
  }
  if (!events.empty()) {
    fmt::format_to(out, ", \\\n     NaN with lines dt (4,3) lw 1.5 lc rgb '{}' title {}", kEventColour,
                   GnuplotQuote(options.events_label));
  }
  fmt::format_to(out, "\nunset key\nunset arrow 1\nunset arrow 2\nunset arrow 3\n"
                      "unset mytics\n");
  for (size_t e = 0; e < events.size() && e < kFigureMaxEventLabels; ++e) {
    fmt::format_to(out, "unset label {}\n", 100 + e);
  }

  // (b): the error, log axis, with the extinction's scale on the right.
  set_panel(1);
  {
    const ErrorAxis axis = FitErrorAxis(envelope.min_value[error_column], envelope.max_value[error_column]);
    fmt::format_to(out,
                   "set logscale y\nset logscale y2\n"
                   "set yrange [{0:.6g}:{1:.6g}]\nset y2range [{0:.6g}:{1:.6g}]\n"
                   "set ytics nomirror autofreq format '%g'\nunset mytics\n"
                   "set ylabel 'error (deg)' noenhanced\n"
                   "set y2tics ({2})\n"
                   "set y2label 'extinction (dB)' noenhanced\n",
                   axis.min_deg, axis.max_deg, axis.extinction_tics);
    fmt::format_to(out, "plot $error using 1:($2 > {:.6g} ? $2 : {:.6g}) with lines lc rgb '{}' notitle\n",
                   axis.min_deg, axis.min_deg, kErrorColour);
    fmt::format_to(out, "unset logscale y\nunset logscale y2\nunset y2tics\nunset y2label\n"
                        "set ytics mirror\n");
  }

  // (c), (d), …: one control signal each, y range fitted to its extremes (and its range's guide
  // lines when they are near).
  const int plot_height_px = options.panel_height_px - 2 * kPanelGapPx;
  const int tick_intervals = std::max(2, plot_height_px / kYTickSpacingPx);
  for (int i = 0; i < control_count; ++i) {
    set_panel(2 + i);
    const std::string& name = controls[static_cast<size_t>(i)];
    double lo = envelope.min_value[first_control + static_cast<size_t>(i)];
    double hi = envelope.max_value[first_control + static_cast<size_t>(i)];
    std::vector<double> guides;
    std::string off_scale;
    if (!options.control_ranges.empty() && std::isfinite(lo)) {
      const auto [range_min, range_max] = options.control_ranges[static_cast<size_t>(i)];
      // Near: the span with the bound at most 3× the signal's own (at least 1 φ unit).
      const double span = std::max(hi - lo, 1.0);
      for (const double bound : {range_min, range_max}) {
        if (!std::isfinite(bound)) continue;
        if (std::max(hi, bound) - std::min(lo, bound) <= 3.0 * span) {
          guides.push_back(bound);
        } else {
          off_scale += fmt::format("{}{:g}", off_scale.empty() ? "range " : ", ", bound);
        }
      }
      for (const double g : guides) {
        lo = std::min(lo, g);
        hi = std::max(hi, g);
      }
    }
    const YAxis y_axis = FitYAxis(lo, hi, tick_intervals);
    fmt::format_to(out,
                   "set yrange [{:.12g}:{:.12g}]\n"
                   "set ytics {:.12g}\n"
                   "set ylabel {}\n",
                   y_axis.min, y_axis.max, y_axis.tick_step, ControlLabel(name, i));
    for (size_t g = 0; g < guides.size(); ++g) {
      fmt::format_to(out,
                     "set arrow {} from graph 0, first {:.12g} to graph 1, first {:.12g} nohead "
                     "dt (4,3) lc rgb '{}' lw 1.2 front\n",
                     20 + g, guides[g], guides[g], kRangeColour);
    }
    if (!off_scale.empty()) {
      fmt::format_to(out, "set label 3 {} at graph 0.99, graph 0.9 right noenhanced font ',9' tc rgb '{}'\n",
                     GnuplotQuote(off_scale + " (off scale)"), kRangeColour);
    }
    if (!std::isfinite(lo)) {
      fmt::format_to(out, "set label 2 'no finite values' at graph 0.5, graph 0.5 center\n");
    }
    fmt::format_to(out, "plot $control_{} using 1:2 with lines lc rgb '{}' notitle\n", i + 1,
                   kControlColour);
    fmt::format_to(out, "unset label 2\nunset label 3\nunset arrow 20\nunset arrow 21\n");
  }
  fmt::format_to(out, "unset multiplot\n");

  RunGnuplot(fmt::to_string(script));
  RequireWrittenPng(png_path);
}

namespace {

// The earlier series that `k` lies on (every point within 1 %, the same rates), or k.
size_t CoincidesWith(const std::vector<RateSeries>& series, size_t k) {
  const RateSeries& b = series[k];
  for (size_t j = 0; j < k; ++j) {
    const RateSeries& a = series[j];
    if (a.rate_rad_per_s != b.rate_rad_per_s || a.error_deg.size() != b.error_deg.size() || a.error_deg.empty()) {
      continue;
    }
    bool same = true;
    for (size_t i = 0; i < a.error_deg.size() && same; ++i) {
      const double x = a.error_deg[i];
      const double y = b.error_deg[i];
      same = (x == y) || (std::isfinite(x) && std::isfinite(y) &&
                          std::abs(x - y) <= 0.01 * std::max(std::abs(x), std::abs(y)));
    }
    if (same) return j;
  }
  return k;
}

}  // namespace

std::vector<std::string> RatePlotLabels(const std::vector<RateSeries>& series) {
  std::vector<std::string> labels;
  for (size_t k = 0; k < series.size(); ++k) {
    const size_t j = CoincidesWith(series, k);
    labels.push_back(j == k ? series[k].label
                            : fmt::format("{} (coincides with {})", series[k].label, series[j].label));
  }
  return labels;
}

void WriteRatePlot(const std::string& png_path, const std::string& title,
                   const std::vector<RateSeries>& series,
                   const std::vector<RateReferenceLine>& references) {
  if (series.empty()) throw std::invalid_argument("WriteRatePlot: no series");
  RequireOutputDirectory(png_path);
  bool any_point = false;
  for (const RateSeries& s : series) {
    if (s.rate_rad_per_s.size() != s.error_deg.size()) {
      throw std::invalid_argument(fmt::format(
          "WriteRatePlot: series '{}' has {} rates but {} errors", s.label,
          s.rate_rad_per_s.size(), s.error_deg.size()));
    }
    for (size_t i = 0; i < s.error_deg.size(); ++i) {
      if (IsDrawableOnLogAxes(s.rate_rad_per_s[i], s.error_deg[i])) any_point = true;
    }
  }
  if (!any_point) {
    throw std::invalid_argument(
        "WriteRatePlot: no point with a finite, positive rate and error to draw on log axes");
  }

  // The ranges are computed here: gnuplot's own log autoscale widens [1e3, 1e6] to [1e2, 1e6]
  // (log10(1000) rounds to 2.9999999999999996 in its arithmetic) and puts markers on the frame.
  double rate_min = std::numeric_limits<double>::infinity();
  double rate_max = 0.0;
  double error_min = std::numeric_limits<double>::infinity();
  double error_max = 0.0;
  for (const RateSeries& s : series) {
    for (size_t i = 0; i < s.error_deg.size(); ++i) {
      if (IsDrawableOnLogAxes(s.rate_rad_per_s[i], s.error_deg[i])) {
        rate_min = std::min(rate_min, s.rate_rad_per_s[i]);
        rate_max = std::max(rate_max, s.rate_rad_per_s[i]);
        error_min = std::min(error_min, s.error_deg[i]);
        error_max = std::max(error_max, s.error_deg[i]);
      }
    }
  }
  for (const RateReferenceLine& line : references) {
    if (!IsDrawableOnLogAxes(1.0, line.error_deg)) {
      throw std::invalid_argument(fmt::format(
          "WriteRatePlot: reference line '{}' at {} deg cannot be drawn on log axes", line.label,
          line.error_deg));
    }
    error_min = std::min(error_min, line.error_deg);
    error_max = std::max(error_max, line.error_deg);
  }
  const DecadeRange x_range = FitDecades(rate_min, rate_max);
  const DecadeRange y_range = FitDecades(error_min, error_max);

  fmt::memory_buffer script;
  auto out = fmt::appender(script);
  AppendPreamble(&script, png_path, kRatePlotWidthPx, kRatePlotHeightPx);
  fmt::format_to(out, "set xrange [{:.6g}:{:.6g}]\nset yrange [{:.6g}:{:.6g}]\n", x_range.min,
                 x_range.max, y_range.min, y_range.max);
  for (size_t k = 0; k < series.size(); ++k) {
    fmt::format_to(out, "$series_{} << EOD\n", k);
    const RateSeries& s = series[k];
    for (size_t i = 0; i < s.error_deg.size(); ++i) {
      if (IsDrawableOnLogAxes(s.rate_rad_per_s[i], s.error_deg[i])) {
        fmt::format_to(out, "{:.12g} {:.12g}\n", s.rate_rad_per_s[i], s.error_deg[i]);
      }
    }
    fmt::format_to(out, "NaN NaN\nEOD\n");  // keeps a block with no drawable point valid
  }
  fmt::format_to(out,
                 "set logscale xy\n"
                 "set format x '10^{{%L}}'\n"
                 "set format y '10^{{%L}}'\n"
                 "set mxtics 10\n"
                 "set mytics 10\n"
                 "set grid xtics ytics mxtics mytics lc rgb '#DDDDDD' lw 1 dt 1, "
                 "lc rgb '#F2F2F2' lw 1 dt 1\n"
                 "set xlabel 'Input SOP rotation rate (rad/s)'\n"
                 "set ylabel 'Mean error (deg)'\n"
                 "set key top left Left reverse samplen 2 spacing 1.2 box lc rgb '#CCCCCC' "
                 "opaque\n");
  if (!title.empty()) fmt::format_to(out, "set title {} noenhanced font ',13'\n", GnuplotQuote(title));
  for (const RateReferenceLine& line : references) {
    fmt::format_to(out,
                   "set arrow from graph 0, first {0:.12g} to graph 1, first {0:.12g} nohead "
                   "dt 2 lw 1.2 lc rgb '{1}'\n"
                   "set label {2} noenhanced at graph 0.98, first {0:.12g} right offset 0,0.6 "
                   "textcolor rgb '{1}'\n",
                   line.error_deg, kTargetColour, GnuplotQuote(line.label));
  }
  const std::vector<std::string> labels = RatePlotLabels(series);
  fmt::format_to(out, "plot ");
  for (size_t k = 0; k < series.size(); ++k) {
    const bool hidden = CoincidesWith(series, k) != k;
    fmt::format_to(out,
                   "{}$series_{} using 1:2 with linespoints lw 1.5 {}pt {} ps 1.1 lc rgb '{}' "
                   "title {} noenhanced",
                   k == 0 ? "" : ", \\\n     ", k, hidden ? "dt (5,4) " : "",
                   kSeriesPointTypes[k % kSeriesPointTypes.size()],
                   kSeriesColours[k % kSeriesColours.size()], GnuplotQuote(labels[k]));
  }
  fmt::format_to(out, "\n");

  RunGnuplot(fmt::to_string(script));
  RequireWrittenPng(png_path);
}

}  // namespace dpc
