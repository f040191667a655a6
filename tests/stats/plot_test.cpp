// The report's figures (stats/src/plot.cpp) read back by OpenCV, a reader this project did
// not write: bar heights in proportion to the means on a common baseline, box heights in
// proportion to the Tukey hinges' spread, both formats written, and a chart without data
// refused.

#include "hapticlab/stats/plot.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "hapticlab/core/status.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::plot_test {
namespace {

// The palette's first two colours (Okabe-Ito blue, orange), as OpenCV's BGR.
const cv::Vec3b kBlue(178, 114, 0), kOrange(0, 159, 230);

// The tallest unbroken run of `colour` in any one column: [top row, bottom row] (-1 when
// absent). Unbroken: the legend's squares in the same colour lie above the bars.
struct Extent {
  int top = -1, bottom = -1;
  int height() const { return top < 0 ? 0 : bottom - top + 1; }
};
Extent TallestColumn(const cv::Mat& img, const cv::Vec3b& colour) {
  Extent best;
  for (int x = 0; x < img.cols; ++x) {
    Extent run;
    for (int y = 0; y <= img.rows; ++y) {
      if (y < img.rows && img.at<cv::Vec3b>(y, x) == colour) {
        if (run.top < 0) run.top = y;
        run.bottom = y;
      } else if (run.top >= 0) {
        if (run.height() > best.height()) best = run;
        run = {};
      }
    }
  }
  return best;
}

// The tallest extent of `colour` in any one column, first row to last (a box plot's box
// is split by its median line).
Extent TallestSpan(const cv::Mat& img, const cv::Vec3b& colour) {
  Extent best;
  for (int x = 0; x < img.cols; ++x) {
    Extent e;
    for (int y = 0; y < img.rows; ++y)
      if (img.at<cv::Vec3b>(y, x) == colour) {
        if (e.top < 0) e.top = y;
        e.bottom = y;
      }
    if (e.height() > best.height()) best = e;
  }
  return best;
}

// The pHYs chunk's horizontal resolution (0: none), read from the PNG's bytes.
std::uint32_t PngPixelsPerMetre(const std::string& file) {
  const std::string png = test::ReadFile(file);
  const auto at = png.find("pHYs");
  if (at == std::string::npos || at + 13 > png.size()) return 0;
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(png[at + 4 + i]);
  return png[at + 12] == 1 ? v : 0;
}

// The plot frame's right edge: the rightmost column that is dark (antialiased black) over
// half the image's height.
int FrameRight(const cv::Mat& img) {
  int right = -1;
  for (int x = 0; x < img.cols; ++x) {
    int dark = 0;
    for (int y = 0; y < img.rows; ++y) {
      const auto& p = img.at<cv::Vec3b>(y, x);
      dark += p[0] < 128 && p[1] < 128 && p[2] < 128;
    }
    if (dark > img.rows / 2) right = x;
  }
  return right;
}

// A PDF read from its bytes (ISO 32000-1): the header, the number of page objects (/Type /Page,
// not /Pages), the first page's MediaBox [x0 y0 x1 y1] in points, and the end-of-file marker
// in the last 1024 bytes.
struct PdfFacts {
  bool header = false, eof = false;
  int pages = 0;
  double width_pt = 0, height_pt = 0;
};
PdfFacts ReadPdf(const std::string& file) {
  const std::string pdf = test::ReadFile(file);
  PdfFacts f;
  f.header = pdf.rfind("%PDF-1.", 0) == 0;
  f.eof = pdf.find("%%EOF", pdf.size() > 1024 ? pdf.size() - 1024 : 0) != std::string::npos;
  for (auto at = pdf.find("/Type /Page"); at != std::string::npos;
       at = pdf.find("/Type /Page", at + 1))
    f.pages += at + 11 < pdf.size() && pdf[at + 11] != 's';
  const auto box = pdf.find("/MediaBox");
  if (box != std::string::npos) {
    double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    if (std::sscanf(pdf.c_str() + box, "/MediaBox [ %lf %lf %lf %lf", &x0, &y0, &x1, &y1) == 4 ||
        std::sscanf(pdf.c_str() + box, "/MediaBox [%lf %lf %lf %lf", &x0, &y0, &x1, &y1) == 4) {
      f.width_pt = x1 - x0;
      f.height_pt = y1 - y0;
    }
  }
  return f;
}

TEST(Plot, EveryFigureIsAlsoAOnePagePdfOfTheFigureSize) {
  test::TempDir dir;
  BarChart c{.title = "t", .x_label = "x", .y_label = "score", .error_label = "95% CI"};
  c.groups = {"A", "B"};
  c.series = {{.name = "FF", .mean = {40, 60}, .err = {3, 3}}};
  BoxPlot b{.title = "t", .x_label = "method", .y_label = "score"};
  b.groups = {"FF"};
  b.samples = {{40, 50, 55, 60, 90}};
  LinePlot l{.title = "power", .x_label = "n", .y_label = "power", .x = {8, 12}};
  l.series = {{"method", {0.4, 0.9}}};
  QqPlot q{.title = "residuals", .y_label = "residual", .sample = {-1, 0, 0.5, 2}};
  for (const auto& files : {DrawBarChart(c, dir.File("bar")), DrawBoxPlot(b, dir.File("box")),
                            DrawLinePlot(l, dir.File("line")), DrawQqPlot(q, dir.File("qq"))}) {
    ASSERT_EQ(files.size(), 3U);
    ASSERT_EQ(files[2].substr(files[2].size() - 4), ".pdf") << files[2];
    const auto f = ReadPdf(files[2]);
    EXPECT_TRUE(f.header) << files[2];
    EXPECT_TRUE(f.eof) << files[2];
    EXPECT_EQ(f.pages, 1) << files[2];
    // 6.5 x 3.8 inches at 72 points per inch (PLplot rounds the page to whole points).
    EXPECT_NEAR(f.width_pt, kFigureWidthInches * 72, 1.0) << files[2];
    EXPECT_NEAR(f.height_pt, kFigureHeightInches * 72, 1.0) << files[2];
  }
}

TEST(Plot, BarHeightsAreProportionalToTheMeans) {
  test::TempDir dir;
  BarChart c{.title = "t", .x_label = "x", .y_label = "score", .error_label = "95% CI"};
  c.groups = {""};
  c.series = {{.name = "FF", .mean = {80}, .err = {5}},
              {.name = "Hybrid", .mean = {40}, .err = {0}}};
  const auto files = DrawBarChart(c, dir.File("bars"));
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0], dir.File("bars.svg"));
  EXPECT_NE(test::ReadFile(files[0]).find("<svg"), std::string::npos);
  const cv::Mat img = cv::imread(files[1], cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty()) << files[1];
  // 6.5 x 3.8 inches at 300 dpi, and the PNG says so (pHYs: 11811 pixels per metre).
  EXPECT_EQ(img.cols, 1950);
  EXPECT_EQ(img.rows, 1140);
  EXPECT_EQ(PngPixelsPerMetre(files[1]), 11811u);
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
  // Tukey's hinges: 20 and 60; 45 and 55 (0 and 100 are outliers there, so a box drawn
  // from the range or the whiskers would be placed elsewhere).
  p.samples = {{0, 10, 20, 30, 40, 50, 60, 70, 80}, {0, 45, 50, 55, 100}};
  p.y_max = 110;
  const auto files = DrawBoxPlot(p, dir.File("box"));
  const cv::Mat img = cv::imread(files.at(1), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  const auto wide = TallestSpan(img, kBlue), narrow = TallestSpan(img, kOrange);
  ASSERT_GT(wide.height(), 50);
  ASSERT_GT(narrow.height(), 5);
  // The wide box's fill (inside its one-pixel outline) spans 20..60: the rows of any value.
  const double px_per_unit = (wide.height() + 1) / 40.0;
  const auto row = [&](double v) { return wide.bottom + 0.5 - (v - 20) * px_per_unit; };
  EXPECT_NEAR(narrow.top - 0.5, row(55), 2);
  EXPECT_NEAR(narrow.bottom + 0.5, row(45), 2);
}

TEST(Plot, LinePlotWritesBothFormatsAndEmptyChartsAreRefused) {
  test::TempDir dir;
  LinePlot l{.title = "spectrum", .x_label = "f [Hz]", .y_label = "PSD", .x = {1, 2, 3}};
  l.series = {{"measured", {1, 10, 100}}, {"synthesized", {0, 0, 0}}};  // log of 0 is clamped
  l.log_y = true;
  const auto files = DrawLinePlot(l, dir.File("line"));
  ASSERT_EQ(files.size(), 3u);
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

TEST(Plot, TheLegendSitsOutsideTheDataArea) {
  // Two groups x two series: the legend's colour boxes lie right of the frame, the bars left.
  test::TempDir dir;
  BarChart c{.title = "Hybrid realism: roughness",
             .x_label = "material",
             .y_label = "score",
             .error_label = "95% within-subject CI (Cousineau-Morey)"};
  c.groups = {"Cork", "Denim"};
  c.series = {{.name = "FF", .mean = {90, 95}, .err = {3, 3}},
              {.name = "Hybrid", .mean = {97, 92}, .err = {2, 2}}};
  const auto files = DrawBarChart(c, dir.File("legend"));
  const cv::Mat img = cv::imread(files.at(1), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  const int frame = FrameRight(img);
  ASSERT_GT(frame, img.cols / 2);
  for (const auto& colour : {kBlue, kOrange}) {
    int inside = 0, outside = 0;
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x)
        if (img.at<cv::Vec3b>(y, x) == colour) (x < frame ? inside : outside) += 1;
    EXPECT_GT(inside, 1000) << "the bars";
    EXPECT_GT(outside, 100) << "the legend's box";
  }
  // The bars reach up to 97 % of the scale: nothing of the legend lies over them.
  EXPECT_GT(TallestColumn(img, kOrange).height(), 500);
}

TEST(Plot, PowerLinesHaveMarkersAndQqPlotsTheirPoints) {
  test::TempDir dir;
  LinePlot l{.title = "power", .x_label = "participants", .y_label = "power", .x = {8, 12, 16}};
  l.series = {{"roughness method", {0.3, 0.7, 0.9}}};
  l.hlines = {{0.8, "power 0.8"}};
  l.vlines = {{16, "n = 16"}};
  l.y_min = 0;
  l.y_max = 1;
  l.markers = true;
  const auto with = DrawLinePlot(l, dir.File("with"));
  l.markers = false;
  const auto without = DrawLinePlot(l, dir.File("without"));
  const auto count = [](const std::string& file) {
    const cv::Mat img = cv::imread(file, cv::IMREAD_COLOR);
    int n = 0;
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x) n += img.at<cv::Vec3b>(y, x) == kBlue;
    return n;
  };
  // The markers add blue pixels along the curve beyond the line's own.
  EXPECT_GT(count(with.at(1)), count(without.at(1)) + 200);
  QqPlot q{.title = "residuals", .y_label = "residual", .sample = {-2, -1, -0.5, 0, 0.4, 1, 2.2}};
  const auto qq = DrawQqPlot(q, dir.File("qq"));
  EXPECT_GT(count(qq.at(1)), 100);  // the points (palette slot 1)
  EXPECT_EQ(PngPixelsPerMetre(qq.at(1)), 11811u);
  EXPECT_THROW(DrawQqPlot(QqPlot{.sample = {1, 2}}, dir.File("e")), PreconditionError);
}

}  // namespace
}  // namespace hapticlab::stats::plot_test
