#pragma once
// Paper-style figures rendered with gnuplot (pngcairo), like Figs. 3–5 of the paper:
//
//   (a)      s1, s2, s3 of S_out against time, y in [−1.05, 1.05], a legend, dashed horizontal
//            lines at the target's components and a dashed vertical line where the DPC is
//            activated (when given);
//   (b)      the pointing error to the target (deg, log axis) with its extinction on the right
//            axis (dB: 20·log10 tan(error/2), the power a polarizer aligned with the target
//            passes of the orthogonal state, relative to the aligned one);
//   (c), (d), …  one panel per control signal φ_i against time, y label φ_i (and the column's
//            name when it is not phi_i), y range fitted to the signal's extremes; the control's
//            range [min, max] (FigureOptions::control_ranges) as dashed guide lines when it lies
//            near the signal (the y range widened to show it), else named in the panel.
//
// All panels share one time axis (t · time_scale, in time_unit); only the bottom panel carries
// tick labels and the axis label. The activation line is drawn in every panel.
//
// Layout, in pixels (a PNG of width_px × PaperFigureHeightPx(controls, options)):
//
//   top band      kFigureTitleBandPx when the title is non-empty, else kFigureNoTitleBandPx
//   panels        (2 + controls) × panel_height_px, panel letters in the left margin
//   bottom band   kFigureAxisBandPx (time tick labels and axis label)
//   left / right  kFigureLeftMarginPx (letters, y labels, tick labels) /
//                 kFigureRightMarginPx (the legend of panel (a))
//
// Large traces. A trace of any length is drawn from its M4 envelope (trace_envelope.h): the
// CSV is streamed twice and each column reduced to ≤ 4 points per pixel column of the plot
// area, so gnuplot draws the same picture from ~4·width points per series instead of every
// row (gnuplot took 20 s and 250 MB to draw 5e5 rows × 7 series directly). Memory is
// independent of the trace length; the extremes (outliers) are kept exactly.
//
// Not for the real-time path: reads files, runs gnuplot (gnuplot_runner.h).

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dpc/optics/stokes.h"

namespace dpc {

/// A moment marked in every panel by a dotted vertical line, its label above panel (a) (e.g. a
/// controller switch).
struct FigureEvent {
  double t_s = 0.0;
  std::string label;
};

/// At most this many events and shaded intervals are drawn (the first ones); at most
/// kFigureMaxEventLabels events are labelled (more would overlap).
inline constexpr size_t kFigureMaxMarks = 200;
inline constexpr size_t kFigureMaxEventLabels = 12;

struct FigureOptions {
  /// Figure title above panel (a), drawn verbatim; empty: no title (and a thinner top band).
  std::string title;
  /// Time at which the DPC was switched on: a dashed vertical line in every panel (none when it
  /// lies outside the trace's time range).
  std::optional<double> activation_s;
  /// The target SOP S* (a unit Stokes vector): dashed horizontal lines at its three components
  /// in panel (a).
  std::optional<StokesVector> target_point;
  /// Each control's range {min, max}, in the trace's order (one per control, or none at all);
  /// a bound that is not finite is not drawn.
  std::vector<std::pair<double, double>> control_ranges;
  /// Intervals [from_s, to_s] shaded in every panel (e.g. the driver holding), named
  /// `shaded_label` in panel (a)'s key; clipped to the trace's time range.
  std::vector<std::pair<double, double>> shaded_intervals;
  std::string shaded_label = "driver holding";
  /// Events (e.g. controller switches), named `events_label` in panel (a)'s key.
  std::vector<FigureEvent> events;
  std::string events_label = "controller switch";
  /// PNG width; at least kFigureMinWidthPx.
  int width_px = 1000;
  /// Height of each panel; at least kFigureMinPanelHeightPx.
  int panel_height_px = 170;
  /// Plotted time = t_s · time_scale (1e3: milliseconds); finite and positive.
  double time_scale = 1e3;
  /// The unit of the plotted time, for the axis label "Time (<time_unit>)".
  std::string time_unit = "ms";
};

inline constexpr int kFigureLeftMarginPx = 95;
inline constexpr int kFigureRightMarginPx = 110;
inline constexpr int kFigureTitleBandPx = 40;
inline constexpr int kFigureNoTitleBandPx = 14;
inline constexpr int kFigureAxisBandPx = 55;
inline constexpr int kFigureMinWidthPx = kFigureLeftMarginPx + kFigureRightMarginPx + 100;
inline constexpr int kFigureMinPanelHeightPx = 60;

/// The PNG height of a figure with `control_count` control panels:
/// top band + (2 + control_count) · panel_height_px + kFigureAxisBandPx.
int PaperFigureHeightPx(int control_count, const FigureOptions& options);

/// Draws the paper-style figure of the TraceWriter CSV `trace_csv` into `png_path`.
/// The control panels are the trace's control columns (from its header), in order.
/// @throws std::invalid_argument for options out of range (sizes, non-finite time_scale or
///         activation time, a target that is not a unit Stokes vector); std::runtime_error if the trace cannot be read, is not a
///         trace, has no data row with a finite time, if the PNG's directory does not exist, or
///         if gnuplot fails or is not installed (the message carries gnuplot's output).
void WritePaperFigure(const std::string& trace_csv, const std::string& png_path,
                      const FigureOptions& options);

/// One line of a rate plot: the mean pointing error at each input SOP rotation rate.
struct RateSeries {
  std::string label;
  std::vector<double> rate_rad_per_s;
  std::vector<double> error_deg;
};

/// The legend labels of a rate plot: each series' label, and for a series whose every point
/// lies within 1 % of an earlier series' (same rates) " (coincides with <that label>)": one
/// curve hides the other, so the legend says so (the later one is drawn dashed).
std::vector<std::string> RatePlotLabels(const std::vector<RateSeries>& series);

inline constexpr int kRatePlotWidthPx = 800;
inline constexpr int kRatePlotHeightPx = 560;

/// A horizontal dashed line across a rate plot at a given error, with its label.
struct RateReferenceLine {
  double error_deg;
  std::string label;
};

/// A log-log plot of mean error (deg) against input rotation rate (rad/s), one line with points
/// per series, into a kRatePlotWidthPx × kRatePlotHeightPx PNG. The data is written inline in
/// the gnuplot script. Points whose rate or error is not finite and positive cannot be drawn
/// on log axes and are left out. `references` (finite, positive errors) are drawn as dashed
/// horizontal lines, the y range widened to include them.
/// @throws std::invalid_argument if `series` is empty, a series' two vectors differ in length,
///         or no point at all can be drawn; std::runtime_error if the PNG's directory does not
///         exist or gnuplot fails.
void WriteRatePlot(const std::string& png_path, const std::string& title,
                   const std::vector<RateSeries>& series,
                   const std::vector<RateReferenceLine>& references = {});

}  // namespace dpc
