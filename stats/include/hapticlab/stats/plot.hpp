#pragma once
/// @file Report figures through PLplot (cairo devices): bar charts with error bars and
/// significance marks like the dissertation's Figs. 4.5, 5.7 and 5.8, and box plots. Every
/// figure is written as both SVG and PNG.

#include <string>
#include <vector>

namespace hapticlab::stats {

/// One bar series (e.g. a method) over the groups (e.g. materials).
struct BarSeries {
  std::string name;
  std::vector<double> mean;  ///< one per group (NaN: no bar)
  std::vector<double> err;   ///< half-length of the error bar (SE or CI half-width)
};

struct BarChart {
  std::string title, x_label, y_label, error_label;  ///< error_label e.g. "95% CI"
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

/// Writes `<base>.svg` and `<base>.png`. Returns the two paths.
std::vector<std::string> DrawBarChart(const BarChart& chart, const std::string& base);

struct BoxPlot {
  std::string title, x_label, y_label;
  std::vector<std::string> groups;
  std::vector<std::vector<double>> samples;  ///< one sample per group
  double y_min = 0, y_max = 100;
};
/// Tukey box plots (hinges, 1.5 IQR whiskers, outliers as points); `<base>.svg/.png`.
std::vector<std::string> DrawBoxPlot(const BoxPlot& plot, const std::string& base);

/// Curves over a common x axis (e.g. measured and synthesized spectra, Figs. 3.5/3.6).
struct LinePlot {
  std::string title, x_label, y_label;
  std::vector<double> x;
  std::vector<std::pair<std::string, std::vector<double>>> series;  ///< name, y per x
  bool log_y = false;  ///< plot log10(y) (labelled as such)
  /// A smaller line under the title (e.g. the model the curves assume); also the SVG's <desc>.
  std::string note;
};
/// `<base>.svg` and `<base>.png`.
std::vector<std::string> DrawLinePlot(const LinePlot& plot, const std::string& base);

}  // namespace hapticlab::stats
