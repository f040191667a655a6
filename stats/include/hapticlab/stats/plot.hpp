#pragma once
/// @file Report figures through PLplot (cairo devices): bar charts with error bars and
/// significance marks like the dissertation's Figs. 4.5, 5.7 and 5.8, box plots, line plots
/// and normal Q-Q plots. Every figure is written as SVG and PDF (vector, sized in inches) and
/// as PNG at 300 dpi (the resolution recorded in the file's pHYs chunk), the journals' minimum for
/// line art with shading. Legends sit outside the data area, to the right.

#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace hapticlab::stats {

/// One bar series (e.g. a method) over the groups (e.g. materials).
struct BarSeries {
  std::string name;
  std::vector<double> mean;  ///< one per group (NaN: no bar)
  std::vector<double> err;   ///< half-length of the error bar (SE or CI half-width)
};

/// Figures are 6.5 x 3.8 inches (a journal's full text width); the PNG is 300 dpi.
inline constexpr double kFigureWidthInches = 6.5, kFigureHeightInches = 3.8, kPngDpi = 300;

struct BarChart {
  /// error_label names the error bars in a note under the chart ("error bars: <label>"),
  /// e.g. "95% within-subject CI (Cousineau-Morey)".
  std::string title, x_label, y_label, error_label;
  /// Groups along the x axis; a single unnamed group ({""}) labels each bar with its series.
  std::vector<std::string> groups;
  std::vector<BarSeries> series;
  std::vector<std::string> group_marks;  ///< text above each group (letters), optional
  /// Significance brackets between series within a single-group chart: (i, j, "**").
  struct Mark {
    int a, b;
    std::string stars;
  };
  std::vector<Mark> marks;
  double y_min = 0, y_max = 100;
};

/// Writes `<base>.svg`, `<base>.png` and `<base>.pdf` (one page). Returns the three paths in
/// that order; so do the other Draw functions.
std::vector<std::string> DrawBarChart(const BarChart& chart, const std::string& base);

struct BoxPlot {
  std::string title, x_label, y_label;
  std::vector<std::string> groups;
  std::vector<std::vector<double>> samples;  ///< one sample per group
  double y_min = 0, y_max = 100;
};
/// Tukey box plots (hinges, 1.5 IQR whiskers, outliers as points); `<base>.svg/.png/.pdf`.
std::vector<std::string> DrawBoxPlot(const BoxPlot& plot, const std::string& base);

/// Curves over a common x axis (e.g. measured and synthesized spectra, Figs. 3.5/3.6).
struct LinePlot {
  std::string title, x_label, y_label;
  std::vector<double> x;
  std::vector<std::pair<std::string, std::vector<double>>> series;  ///< name, y per x
  bool log_y = false;    ///< plot log10(y) (labelled as such)
  bool markers = false;  ///< a symbol at each point (a different one per series)
  /// Reference lines across the plot (y value or x value, label), e.g. power 0.8.
  std::vector<std::pair<double, std::string>> hlines, vlines;
  double y_min = NAN, y_max = NAN;  ///< fixed y range (NaN: from the data)
  /// A smaller line under the title (e.g. the model the curves assume); also the SVG's <desc>.
  std::string note;
};
/// `<base>.svg/.png/.pdf`.
std::vector<std::string> DrawLinePlot(const LinePlot& plot, const std::string& base);

/// Normal Q-Q plot: the sorted sample against standard normal quantiles at R's ppoints(n),
/// with the line through the first and third quartiles (R's qqnorm and qqline).
struct QqPlot {
  std::string title, y_label;
  std::vector<double> sample;
};
/// `<base>.svg/.png/.pdf`. @throws PreconditionError with fewer than 3 values.
std::vector<std::string> DrawQqPlot(const QqPlot& plot, const std::string& base);

/// A figure drawn by `draw` with PLplot calls (the palette's colours 1-8, black 15) on the
/// house page: `<base>.svg` and `<base>.png` (300 dpi), as the figures above.
std::vector<std::string> DrawFigure(const std::string& base, const std::function<void()>& draw);

/// A forest plot (plot_forest.cpp): one row per estimate with its interval, top to bottom;
/// pooled rows as diamonds (colour 2), the others as squares (colour 1); vertical reference
/// lines (e.g. no effect, the original study's effect).
struct ForestPlot {
  std::string title, x_label, note;
  struct Row {
    std::string label;
    double estimate = 0, low = 0, high = 0;  ///< NaN interval: the point only
    bool pooled = false;
  };
  std::vector<Row> rows;
  std::vector<std::pair<double, std::string>> vlines;  ///< x value, label
};
/// `<base>.svg` and `<base>.png`. @throws PreconditionError without rows.
std::vector<std::string> DrawForestPlot(const ForestPlot& plot, const std::string& base);

}  // namespace hapticlab::stats
