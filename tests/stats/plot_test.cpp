// The report's figures (stats/src/plot.cpp) read back by OpenCV, a reader this project did
// not write: bar heights in proportion to the means on a common baseline, box heights in
// proportion to the Tukey hinges' spread, both formats written, and a chart without data
// refused.

#include "hapticlab/stats/plot.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "hapticlab/core/status.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats {
namespace {

// The palette's first two colours (Okabe-Ito blue, orange), as OpenCV's BGR.
const cv::Vec3b kBlue(178, 114, 0), kOrange(0, 159, 230);

// The tallest run of `colour` in any one column: [top row, bottom row] (-1 when absent).
struct Extent {
  int top = -1, bottom = -1;
  int height() const { return bottom - top + 1; }
};
Extent TallestColumn(const cv::Mat& img, const cv::Vec3b& colour) {
  Extent best;
  for (int x = 0; x < img.cols; ++x) {
    Extent e;
    for (int y = 0; y < img.rows; ++y)
      if (img.at<cv::Vec3b>(y, x) == colour) {
        if (e.top < 0) e.top = y;
        e.bottom = y;
      }
    if (e.top >= 0 && e.height() > best.height()) best = e;
  }
  return best;
}

TEST(Plot, BarHeightsAreProportionalToTheMeans) {
  test::TempDir dir;
  BarChart c{.title = "t", .x_label = "x", .y_label = "score", .error_label = "95% CI"};
  c.groups = {""};
  c.series = {{.name = "FF", .mean = {80}, .err = {5}}, {.name = "Hybrid", .mean = {40}, .err = {0}}};
  const auto files = DrawBarChart(c, dir.File("bars"));
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0], dir.File("bars.svg"));
  EXPECT_NE(test::ReadFile(files[0]).find("<svg"), std::string::npos);
  const cv::Mat img = cv::imread(files[1], cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty()) << files[1];
  EXPECT_EQ(img.cols, 900);
  EXPECT_EQ(img.rows, 520);
  const auto a = TallestColumn(img, kBlue), b = TallestColumn(img, kOrange);
  ASSERT_GT(a.height(), 100) << "no bar of the first series";
  ASSERT_GT(b.height(), 50) << "no bar of the second series";
  // One baseline (y = 0), heights 80 : 40 (the outline and antialiasing: a pixel or two).
  EXPECT_NEAR(a.bottom, b.bottom, 1);
  EXPECT_NEAR(static_cast<double>(a.height()) / b.height(), 2.0, 0.04);
}

TEST(Plot, BoxHeightsFollowTheHinges) {
  test::TempDir dir;
  BoxPlot p{.title = "t", .x_label = "method", .y_label = "score"};
  p.groups = {"wide", "narrow"};
  // Tukey's hinges: 20 and 60 (spread 40); 40 and 60 (spread 20).
  p.samples = {{0, 10, 20, 30, 40, 50, 60, 70, 80}, {30, 40, 50, 60, 70}};
  const auto files = DrawBoxPlot(p, dir.File("box"));
  const cv::Mat img = cv::imread(files.at(1), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  const auto wide = TallestColumn(img, kBlue), narrow = TallestColumn(img, kOrange);
  ASSERT_GT(narrow.height(), 20);
  // Both boxes reach up to 60: the same top row.
  EXPECT_NEAR(wide.top, narrow.top, 1);
  EXPECT_NEAR(static_cast<double>(wide.height()) / narrow.height(), 2.0, 0.06);
}

TEST(Plot, LinePlotWritesBothFormatsAndEmptyChartsAreRefused) {
  test::TempDir dir;
  LinePlot l{.title = "spectrum", .x_label = "f [Hz]", .y_label = "PSD", .x = {1, 2, 3}};
  l.series = {{"measured", {1, 10, 100}}, {"synthesized", {0, 0, 0}}};  // log of 0 is clamped
  l.log_y = true;
  const auto files = DrawLinePlot(l, dir.File("line"));
  ASSERT_EQ(files.size(), 2u);
  const cv::Mat img = cv::imread(files[1], cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_GT(TallestColumn(img, kBlue).height(), 0);  // the first curve is drawn
  EXPECT_THROW(DrawLinePlot(LinePlot{}, dir.File("e")), PreconditionError);
  EXPECT_THROW(DrawBarChart(BarChart{}, dir.File("e")), PreconditionError);
  BoxPlot mismatched;
  mismatched.groups = {"a", "b"};
  mismatched.samples = {{1}};
  EXPECT_THROW(DrawBoxPlot(mismatched, dir.File("e")), PreconditionError);
}

}  // namespace
}  // namespace hapticlab::stats
