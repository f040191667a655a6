// The forest plot of the multi-site report (stats/multisite.hpp): estimates with intervals.
#include <plplot/plplot.h>

#include <algorithm>
#include <cmath>

#include "hapticlab/core/status.hpp"
#include "hapticlab/stats/plot.hpp"

namespace hapticlab::stats {

namespace {

void DrawForest(const ForestPlot& f) {
  const auto n = static_cast<double>(f.rows.size());
  double lo = 0, hi = 0;  // the range holds 0, every interval and every reference line
  for (const auto& r : f.rows)
    for (double v : {r.estimate, r.low, r.high})
      if (std::isfinite(v)) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
  for (const auto& [x, label] : f.vlines) {
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  if (!(hi > lo)) hi = lo + 1;
  const double pad = 0.08 * (hi - lo);
  lo -= pad;
  hi += pad;
  plcol0(15);
  plschr(0, 0.8);
  plvpor(0.22, 0.95, 0.2, 0.88);
  plwind(lo, hi, 0.4, n + 0.6);
  plbox("bcnst", 0, 0, "bc", 0, 0);
  pllab(f.x_label.c_str(), "", f.title.c_str());
  for (const auto& [x, label] : f.vlines) {
    plcol0(8);
    pljoin(x, 0.4, x, n + 0.6);
    plschr(0, 0.6);
    plptex(x, n + 0.45, 0, 1, 0.5, label.c_str());
    plschr(0, 0.8);
  }
  const double hx = 0.012 * (hi - lo), hy = 0.18;  // marker half sizes
  for (std::size_t i = 0; i < f.rows.size(); ++i) {
    const auto& r = f.rows[i];
    const double y = n - static_cast<double>(i);  // the first row on top
    plcol0(15);
    plmtex("lv", 0.8, (y - 0.4) / (n + 0.2), 1.0, r.label.c_str());
    if (std::isfinite(r.low) && std::isfinite(r.high)) pljoin(r.low, y, r.high, y);
    if (r.pooled) {
      plcol0(2);
      PLFLT xs[4] = {r.estimate - 1.6 * hx, r.estimate, r.estimate + 1.6 * hx, r.estimate};
      PLFLT ys[4] = {y, y + hy, y, y - hy};
      plfill(4, xs, ys);
    } else {
      plcol0(1);
      PLFLT xs[4] = {r.estimate - hx, r.estimate + hx, r.estimate + hx, r.estimate - hx};
      PLFLT ys[4] = {y - hy, y - hy, y + hy, y + hy};
      plfill(4, xs, ys);
    }
  }
  if (!f.note.empty()) {
    plcol0(15);
    plschr(0, 0.65);
    plmtex("b", 5.6, 1.0, 1.0, f.note.c_str());
    plschr(0, 0.8);
  }
}

}  // namespace

std::vector<std::string> DrawForestPlot(const ForestPlot& plot, const std::string& base) {
  HL_REQUIRE(!plot.rows.empty(), "forest plot without rows");
  return DrawFigure(base, [&] { DrawForest(plot); });
}

}  // namespace hapticlab::stats
