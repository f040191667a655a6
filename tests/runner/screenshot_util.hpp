#pragma once
// What the screenshot tests of the windows (ui_windows_test.cpp) and of the session UI
// (session_ui_test.cpp) share: the count of bright pixels in a drawn item's box.

#include <opencv2/core.hpp>

#include "hapticlab/runner_ui/ui_windows.hpp"

namespace hapticlab::runner::ui::test_screens {

inline int Bright(const cv::Mat& img, const DrawnItem& r, int threshold = 140) {
  int n = 0;
  for (int y = static_cast<int>(r.y0); y < static_cast<int>(r.y1); ++y)
    for (int x = static_cast<int>(r.x0); x < static_cast<int>(r.x1); ++x) {
      if (x < 0 || y < 0 || x >= img.cols || y >= img.rows) continue;
      const auto p = img.at<cv::Vec3b>(y, x);
      if ((p[0] + p[1] + p[2]) / 3 > threshold) ++n;
    }
  return n;
}

}  // namespace hapticlab::runner::ui::test_screens
