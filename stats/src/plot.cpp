#include "hapticlab/stats/plot.hpp"

#include <plplot/plplot.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hapticlab/core/io.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/stats/descriptive.hpp"

namespace hapticlab::stats {
namespace {

// Colour-blind-safe palette (Okabe-Ito), slots 1.. of colour map 0.
constexpr int kPalette[][3] = {{0, 114, 178},  {230, 159, 0}, {0, 158, 115},  {204, 121, 167},
                               {86, 180, 233}, {213, 94, 0},  {240, 228, 66}, {120, 120, 120}};

// Opens one PLplot stream on a cairo device; plend() closes it.
void Begin(const char* device, const std::string& file, int width, int height) {
  plsdev(device);
  plsfnam(file.c_str());
  plspage(0, 0, width, height, 0, 0);
  plscolbg(255, 255, 255);
  plinit();
  plscol0(0, 255, 255, 255);
  plscol0(15, 0, 0, 0);
  for (int i = 0; i < 8; ++i) plscol0(i + 1, kPalette[i][0], kPalette[i][1], kPalette[i][2]);
  pladv(0);
}

void Rect(double x0, double x1, double y0, double y1) {
  PLFLT xs[4] = {x0, x1, x1, x0}, ys[4] = {y0, y0, y1, y1};
  plfill(4, xs, ys);
  plcol0(15);
  PLFLT bx[5] = {x0, x1, x1, x0, x0}, by[5] = {y0, y0, y1, y1, y0};
  plline(5, bx, by);
}

void DrawBars(const BarChart& c) {
  const int ng = static_cast<int>(c.groups.size()), ns = static_cast<int>(c.series.size());
  std::size_t longest = 0;
  for (const auto& g : c.groups) longest = std::max(longest, g.size());
  plvpor(0.1, 0.97, ng > 4 ? 0.34 : 0.17, 0.9);
  plwind(-0.6, ng - 0.4, c.y_min, c.y_max);
  plcol0(15);
  plschr(0, 0.8);
  plbox("bc", 0, 0, "bcnstv", 0, 0);
  pllab("", c.y_label.c_str(), c.title.c_str());
  const double w = 0.8 / std::max(ns, 1);
  // The x-axis label below the group labels (vertical labels take about 0.7 character
  // heights per character).
  plmtex("b", ng > 4 ? 1.5 + 0.7 * static_cast<double>(longest) : 3.0, 0.5, 0.5, c.x_label.c_str());
  // A single unnamed group: each bar is labelled with its series name.
  if (ng == 1 && c.groups[0].empty())
    for (int s = 0; s < ns; ++s)
      plmtex("b", 1.5, (-0.4 + (s + 0.45) * w + 0.6) / (ng + 0.2), 0.5,
             c.series[static_cast<std::size_t>(s)].name.c_str());
  for (int g = 0; g < ng; ++g) {
    // Group label below the axis: vertical when there are many groups.
    const double x = g;
    plcol0(15);
    const double pos = (g + 0.6) / (ng + 0.2);  // the window spans [-0.6, ng - 0.4]
    if (ng > 4)
      plmtex("bv", 0.5, pos, 1.0, c.groups[static_cast<std::size_t>(g)].c_str());
    else
      plmtex("b", 1.5, pos, 0.5, c.groups[static_cast<std::size_t>(g)].c_str());
    double top = c.y_min;
    for (int s = 0; s < ns; ++s) {
      const auto& se = c.series[static_cast<std::size_t>(s)];
      const double m = se.mean[static_cast<std::size_t>(g)];
      if (!std::isfinite(m)) continue;
      const double x0 = x - 0.4 + s * w, x1 = x0 + w * 0.9;
      plcol0(1 + s % 8);
      Rect(x0, x1, c.y_min, m);
      const double e = se.err[static_cast<std::size_t>(g)];
      if (std::isfinite(e) && e > 0) {
        plcol0(15);
        PLFLT xm[1] = {0.5 * (x0 + x1)}, lo[1] = {m - e}, hi[1] = {m + e};
        plerry(1, xm, lo, hi);
      }
      top = std::max(top, m + (std::isfinite(e) ? e : 0));
    }
    if (g < static_cast<int>(c.group_marks.size()) &&
        !c.group_marks[static_cast<std::size_t>(g)].empty()) {
      plcol0(15);
      plptex(x, top + 0.04 * (c.y_max - c.y_min), 1, 0, 0.5,
             c.group_marks[static_cast<std::size_t>(g)].c_str());
    }
  }
  // Significance brackets (single-group charts: between series).
  double level = c.y_max - 0.12 * (c.y_max - c.y_min);
  for (const auto& mk : c.marks) {
    const double xa = -0.4 + (mk.a + 0.45) * w, xb = -0.4 + (mk.b + 0.45) * w;
    plcol0(15);
    pljoin(xa, level, xb, level);
    pljoin(xa, level, xa, level - 0.02 * (c.y_max - c.y_min));
    pljoin(xb, level, xb, level - 0.02 * (c.y_max - c.y_min));
    plptex(0.5 * (xa + xb), level + 0.01 * (c.y_max - c.y_min), 1, 0, 0.5, mk.stars.c_str());
    level -= 0.07 * (c.y_max - c.y_min);
  }
  // Legend: coloured squares with series names along the top.
  for (int s = 0; s < ns; ++s) {
    const double lx = -0.5 + s * (ng + 0.1) / std::max(ns, 1),
                 ly = c.y_max - 0.04 * (c.y_max - c.y_min);
    plcol0(1 + s % 8);
    Rect(lx, lx + 0.05 * (ng + 0.2) / 4, ly - 0.02 * (c.y_max - c.y_min),
         ly + 0.01 * (c.y_max - c.y_min));
    plcol0(15);
    std::string label = c.series[static_cast<std::size_t>(s)].name;
    if (s == 0 && !c.error_label.empty()) label += "   (bars: " + c.error_label + ")";
    plptex(lx + 0.07 * (ng + 0.2) / 4, ly - 0.01 * (c.y_max - c.y_min), 1, 0, 0, label.c_str());
  }
}

void DrawBoxes(const BoxPlot& b) {
  const int ng = static_cast<int>(b.groups.size());
  plvpor(0.1, 0.97, 0.17, 0.9);
  plwind(-0.6, ng - 0.4, b.y_min, b.y_max);
  plcol0(15);
  plschr(0, 0.8);
  plbox("bc", 0, 0, "bcnstv", 0, 0);
  pllab(b.x_label.c_str(), b.y_label.c_str(), b.title.c_str());
  for (int g = 0; g < ng; ++g) {
    const auto& x = b.samples[static_cast<std::size_t>(g)];
    plcol0(15);
    plmtex("b", 1.5, (g + 0.6) / (ng + 0.2), 0.5, b.groups[static_cast<std::size_t>(g)].c_str());
    if (x.empty()) continue;
    const auto f = Outliers(x, QuartileRule::kHinges);
    std::vector<double> s(x);
    std::sort(s.begin(), s.end());
    double lo = s.back(), hi = s.front();
    for (double v : s)
      if (v >= f.lower) lo = std::min(lo, v);
    for (double v : s)
      if (v <= f.upper) hi = std::max(hi, v);
    const double med = Describe(x).median;
    plcol0(1 + g % 8);
    Rect(g - 0.3, g + 0.3, f.q1, f.q3);
    plcol0(15);
    pljoin(g - 0.3, med, g + 0.3, med);
    pljoin(g, f.q3, g, hi);
    pljoin(g, f.q1, g, lo);
    pljoin(g - 0.15, hi, g + 0.15, hi);
    pljoin(g - 0.15, lo, g + 0.15, lo);
    for (std::size_t i : f.outliers) {
      PLFLT px[1] = {static_cast<PLFLT>(g)}, py[1] = {x[i]};
      plpoin(1, px, py, 4);
    }
  }
}

std::string XmlEscaped(const std::string& s) {
  std::string out;
  for (const char c : s) {
    if (c == '&')
      out += "&amp;";
    else if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else
      out += c;
  }
  return out;
}

// cairo draws text as glyph outlines: the SVG gets its title and note as <title> and <desc>
// (what a screen reader or a search reads), right after the opening <svg> tag.
void DescribeSvg(const std::string& file, const std::string& title, const std::string& note) {
  std::string svg = ReadTextFile(file, "figure");
  const auto open = svg.find("<svg");
  const auto end = open == std::string::npos ? open : svg.find('>', open);
  if (end == std::string::npos) throw std::runtime_error(file + ": not an SVG file");
  svg.insert(end + 1,
             "\n<title>" + XmlEscaped(title) + "</title>\n<desc>" + XmlEscaped(note) + "</desc>");
  WriteTextFile(file, svg);
}

template <class F>
std::vector<std::string> Both(const std::string& base, int w, int h, F draw) {
  std::vector<std::string> files;
  for (const auto& [dev, ext] : {std::pair{"svgcairo", ".svg"}, std::pair{"pngcairo", ".png"}}) {
    Begin(dev, base + ext, w, h);
    draw();
    plend();
    files.push_back(base + ext);
  }
  return files;
}

}  // namespace

std::vector<std::string> DrawBarChart(const BarChart& c, const std::string& base) {
  HL_REQUIRE(!c.groups.empty() && !c.series.empty(), "bar chart without data");
  return Both(base, 900, 520, [&] { DrawBars(c); });
}

std::vector<std::string> DrawLinePlot(const LinePlot& l, const std::string& base) {
  HL_REQUIRE(!l.x.empty() && !l.series.empty(), "line plot without data");
  auto files = Both(base, 800, 480, [&] {
    std::vector<std::vector<PLFLT>> ys;
    double lo = 1e300, hi = -1e300;
    for (const auto& [name, y] : l.series) {
      std::vector<PLFLT> v;
      for (double a : y) v.push_back(l.log_y ? std::log10(std::max(a, 1e-12)) : a);
      for (double a : v) {
        lo = std::min(lo, a);
        hi = std::max(hi, a);
      }
      ys.push_back(std::move(v));
    }
    if (!(hi > lo)) hi = lo + 1;
    plcol0(15);
    plschr(0, 0.8);
    plvpor(0.1, 0.97, 0.12, 0.9);
    plwind(l.x.front(), l.x.back(), lo, hi + 0.1 * (hi - lo));
    plbox("bcnst", 0, 0, "bcnstv", 0, 0);
    pllab(l.x_label.c_str(), (l.log_y ? "log10 " + l.y_label : l.y_label).c_str(), l.title.c_str());
    if (!l.note.empty()) {
      plschr(0, 0.6);
      plmtex("t", 0.6, 0.5, 0.5, l.note.c_str());
      plschr(0, 0.8);
    }
    std::vector<PLFLT> x(l.x.begin(), l.x.end());
    for (std::size_t s = 0; s < ys.size(); ++s) {
      plcol0(1 + static_cast<int>(s % 8));
      plline(static_cast<PLINT>(x.size()), x.data(), ys[s].data());
      const double ly = hi + 0.05 * (hi - lo) - 0.06 * (hi - lo) * static_cast<double>(s);
      const double lx = l.x.front() + 0.65 * (l.x.back() - l.x.front());
      pljoin(lx, ly, lx + 0.05 * (l.x.back() - l.x.front()), ly);
      plcol0(15);
      plptex(lx + 0.06 * (l.x.back() - l.x.front()), ly, 1, 0, 0, l.series[s].first.c_str());
    }
  });
  if (!l.note.empty()) DescribeSvg(base + ".svg", l.title, l.note);
  return files;
}

std::vector<std::string> DrawBoxPlot(const BoxPlot& b, const std::string& base) {
  HL_REQUIRE(b.groups.size() == b.samples.size() && !b.groups.empty(), "box plot without data");
  return Both(base, 700, 480, [&] { DrawBoxes(b); });
}

}  // namespace hapticlab::stats
