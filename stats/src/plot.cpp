#include "hapticlab/stats/plot.hpp"

#include <plplot/plplot.h>
#include <zlib.h>

#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <iterator>
#include <stdexcept>
#include <tuple>

#include "hapticlab/core/io.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/stats/descriptive.hpp"

namespace hapticlab::stats {
namespace {

// Colour-blind-safe palette (Okabe-Ito), slots 1.. of colour map 0.
constexpr int kPalette[][3] = {{0, 114, 178},  {230, 159, 0}, {0, 158, 115},  {204, 121, 167},
                               {86, 180, 233}, {213, 94, 0},  {240, 228, 66}, {120, 120, 120}};

// Opens one PLplot stream on a cairo device; plend() closes it. `dpi`: pixels (PNG) or
// points (SVG, PDF) per inch.
void Begin(const char* device, const std::string& file, double dpi) {
  plsdev(device);
  plsfnam(file.c_str());
  plspage(dpi, dpi, static_cast<PLINT>(std::lround(kFigureWidthInches * dpi)),
          static_cast<PLINT>(std::lround(kFigureHeightInches * dpi)), 0, 0);
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

// Markers of the curves (UTF-8 glyphs drawn by plstring, as pllegend draws its symbols).
constexpr const char* kMarkers[] = {"●", "■", "▲", "◆", "▼", "✚", "✖", "★"};

// Legend entries outside the viewport, to the right of the data. `kind` per entry:
// PL_LEGEND_COLOR_BOX (bars, boxes) or PL_LEGEND_LINE | PL_LEGEND_SYMBOL (curves).
void Legend(const std::vector<std::string>& names, const std::vector<PLINT>& kind,
            const std::vector<PLINT>& symbols = {}) {
  const auto n = static_cast<PLINT>(names.size());
  if (n == 0) return;
  std::vector<const char*> text, sym;
  std::vector<PLINT> colours, patterns(names.size(), 0), styles(names.size(), 1);
  std::vector<PLFLT> scales(names.size(), 0.9), widths(names.size(), 1.5),
      sym_scales(names.size(), 1);
  std::vector<PLINT> sym_numbers(names.size(), 1);

  for (std::size_t i = 0; i < names.size(); ++i) {
    text.push_back(names[i].c_str());
    colours.push_back(1 + static_cast<PLINT>(i % 8));
    sym.push_back(kMarkers[(symbols.empty() ? i : static_cast<std::size_t>(symbols[i])) % 8]);
  }
  std::vector<PLINT> text_colours(names.size(), 15);
  PLFLT w = 0, h = 0;
  // Right of the viewport, its middle level with the viewport's.
  pllegend(&w, &h, 0, PL_POSITION_RIGHT | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT, 0.02, 0.0,
           0.04, 0, 15, 1, n, 1, n, kind.data(), 0.8, 0.8, 1.8, 0.0, text_colours.data(),
           text.data(), colours.data(), patterns.data(), scales.data(), widths.data(),
           colours.data(), styles.data(), widths.data(), colours.data(), sym_scales.data(),
           sym_numbers.data(), sym.data());
  plschr(0, 0.8);
}

// A note under the plot at the right (what error bars or lines show); `offset` in the axis
// labels' character heights.
void Note(const std::string& text, double offset) {
  if (text.empty()) return;
  constexpr double kLabel = 0.8, kNote = 0.65;  // character scales
  plcol0(15);
  plschr(0, kNote);
  plmtex("b", offset * kLabel / kNote, 1.0, 1.0, text.c_str());
  plschr(0, kLabel);
}

// The right edge of the viewport: room for the legend's longest name.
double RightEdge(const std::vector<std::string>& names) {
  std::size_t longest = 0;
  for (const auto& n : names) longest = std::max(longest, n.size());
  return std::clamp(0.95 - 0.009 * static_cast<double>(longest + 6), 0.6, 0.9);
}

void DrawBars(const BarChart& c) {
  const int ng = static_cast<int>(c.groups.size()), ns = static_cast<int>(c.series.size());
  std::size_t longest = 0;
  for (const auto& g : c.groups) longest = std::max(longest, g.size());
  std::vector<std::string> names;
  for (const auto& se : c.series) names.push_back(se.name);
  const bool single = ng == 1 && c.groups[0].empty();
  const double bottom = ng > 4 ? 0.36 : 0.2;
  plvpor(0.1, single ? 0.95 : RightEdge(names), bottom, 0.9);
  plwind(-0.6, ng - 0.4, c.y_min, c.y_max);
  plcol0(15);
  plschr(0, 0.8);
  plbox("bc", 0, 0, "bcnstv", 0, 0);
  pllab("", c.y_label.c_str(), c.title.c_str());
  const double w = 0.8 / std::max(ns, 1);
  // The x-axis label below the group labels (vertical labels take about 0.7 character
  // heights per character).
  const double x_label_at = ng > 4 ? 2.0 + 0.75 * static_cast<double>(longest) : 3.0;
  plmtex("b", x_label_at, 0.5, 0.5, c.x_label.c_str());
  if (!c.error_label.empty()) Note("error bars: " + c.error_label, x_label_at + 1.4);
  // A single unnamed group: each bar is labelled with its series name (no legend needed).
  if (single)
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
  double level = c.y_max - 0.06 * (c.y_max - c.y_min);
  for (const auto& mk : c.marks) {
    const double xa = -0.4 + (mk.a + 0.45) * w, xb = -0.4 + (mk.b + 0.45) * w;
    plcol0(15);
    pljoin(xa, level, xb, level);
    pljoin(xa, level, xa, level - 0.02 * (c.y_max - c.y_min));
    pljoin(xb, level, xb, level - 0.02 * (c.y_max - c.y_min));
    plptex(0.5 * (xa + xb), level + 0.01 * (c.y_max - c.y_min), 1, 0, 0.5, mk.stars.c_str());
    level -= 0.07 * (c.y_max - c.y_min);
  }
  if (!single) Legend(names, std::vector<PLINT>(names.size(), PL_LEGEND_COLOR_BOX));
}

void DrawBoxes(const BoxPlot& b) {
  const int ng = static_cast<int>(b.groups.size());
  plvpor(0.1, 0.95, 0.17, 0.9);
  // A margin around the scale, so whiskers and caps at its ends stay off the frame.
  const double pad = 0.04 * (b.y_max - b.y_min);
  plwind(-0.6, ng - 0.4, b.y_min - pad, b.y_max + pad);
  plcol0(15);
  plschr(0, 0.8);
  plbox("bc", 0, 0, "bcnstv", 0, 0);
  pllab("", b.y_label.c_str(), b.title.c_str());
  plmtex("b", 3.0, 0.5, 0.5, b.x_label.c_str());
  Note("boxes: Tukey's hinges and median; whiskers: 1.5 IQR; points: outliers", 4.4);
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

// `dpi`: the device's units per inch (curves are drawn about 0.6 pt wide on either device).
void DrawLines(const LinePlot& l, double dpi) {
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
  if (std::isfinite(l.y_min)) lo = l.y_min;
  if (std::isfinite(l.y_max)) hi = l.y_max;
  std::vector<std::string> names;
  for (const auto& s : l.series) names.push_back(s.first);
  plcol0(15);
  plschr(0, 0.8);
  plvpor(0.1, RightEdge(names), 0.14, 0.9);
  const double pad_x = l.markers ? 0.03 * (l.x.back() - l.x.front()) : 0;
  const double pad_y = 0.04 * (hi - lo);
  plwind(l.x.front() - pad_x, l.x.back() + pad_x, lo - pad_y, hi + pad_y);
  plbox("bcnst", 0, 0, "bcnstv", 0, 0);
  pllab(l.x_label.c_str(), (l.log_y ? "log10 " + l.y_label : l.y_label).c_str(), l.title.c_str());
  if (!l.note.empty()) {
    plschr(0, 0.6);
    plmtex("t", 0.6, 0.5, 0.5, l.note.c_str());
    plschr(0, 0.8);
  }
  // Reference lines first (dashed grey), so the curves lie on top.
  plcol0(8);
  pllsty(2);
  // Labels where curves rarely are: below a level line at the right end (rising curves
  // are above it there), right of a vertical line low in the plot.
  for (const auto& [y, label] : l.hlines) {
    pljoin(l.x.front() - pad_x, y, l.x.back() + pad_x, y);
    plptex(l.x.back(), y - 0.05 * (hi - lo), 1, 0, 1.0, label.c_str());
  }
  for (const auto& [x, label] : l.vlines) {
    pljoin(x, lo - pad_y, x, hi + pad_y);
    plptex(x + 0.01 * (l.x.back() - l.x.front()), lo + 0.2 * (hi - lo), 1, 0, 0, label.c_str());
  }
  pllsty(1);
  std::vector<PLFLT> x(l.x.begin(), l.x.end());
  for (std::size_t s = 0; s < ys.size(); ++s) {
    plcol0(1 + static_cast<int>(s % 8));
    plwidth(std::max(1.0, 0.6 * dpi / 72));
    plline(static_cast<PLINT>(x.size()), x.data(), ys[s].data());
    plwidth(1);
    if (l.markers) plstring(static_cast<PLINT>(x.size()), x.data(), ys[s].data(), kMarkers[s % 8]);
  }
  Legend(names, std::vector<PLINT>(names.size(),
                                   l.markers ? PL_LEGEND_LINE | PL_LEGEND_SYMBOL : PL_LEGEND_LINE));
}

void DrawQq(const QqPlot& q) {
  std::vector<double> y(q.sample);
  std::sort(y.begin(), y.end());
  const std::size_t n = y.size();
  // R's ppoints(n): (i - a) / (n + 1 - 2a), a = 3/8 for n <= 10, else 1/2.
  const double a = n <= 10 ? 0.375 : 0.5;
  const boost::math::normal normal;
  std::vector<PLFLT> x(n);
  for (std::size_t i = 0; i < n; ++i)
    x[i] = boost::math::quantile(
        normal, (static_cast<double>(i + 1) - a) / (static_cast<double>(n) + 1 - 2 * a));
  // qqline: through the (type 7) quartiles of the sample and of the normal.
  const auto type7 = [&](double p) {
    const double h = (static_cast<double>(n) - 1) * p;
    const auto i = static_cast<std::size_t>(std::floor(h));
    return i + 1 < n ? y[i] + (h - static_cast<double>(i)) * (y[i + 1] - y[i]) : y[i];
  };
  const double zq = boost::math::quantile(normal, 0.75);
  const double slope = (type7(0.75) - type7(0.25)) / (2 * zq);
  const double mid = 0.5 * (type7(0.75) + type7(0.25));
  const double xl = std::min(-2.5, x.front() - 0.2), xh = std::max(2.5, x.back() + 0.2);
  double lo = std::min(y.front(), mid + slope * xl), hi = std::max(y.back(), mid + slope * xh);
  if (!(hi > lo)) hi = lo + 1;
  const double pad = 0.05 * (hi - lo);
  plcol0(15);
  plschr(0, 0.8);
  plvpor(0.12, 0.95, 0.14, 0.9);
  plwind(xl, xh, lo - pad, hi + pad);
  plbox("bcnst", 0, 0, "bcnstv", 0, 0);
  pllab("standard normal quantile", q.y_label.c_str(), q.title.c_str());
  plcol0(8);
  pljoin(xl, mid + slope * xl, xh, mid + slope * xh);
  plcol0(1);
  std::vector<PLFLT> yy(y.begin(), y.end());
  plpoin(static_cast<PLINT>(n), x.data(), yy.data(), 4);
}

// Records the PNG's resolution (pHYs, pixels per metre) right after its header chunk: cairo
// writes none, and journals' checks read it.
void SetPngDpi(const std::string& file, double dpi) {
  std::string png;
  {
    std::ifstream in(file, std::ios::binary);
    png.assign(std::istreambuf_iterator<char>(in), {});
  }
  constexpr std::size_t kAfterIhdr = 8 + 25;  // signature + IHDR (length, type, 13, CRC)
  if (png.size() < kAfterIhdr || png.compare(12, 4, "IHDR") != 0 ||
      png.find("pHYs") != std::string::npos)
    return;
  const auto ppm = static_cast<std::uint32_t>(std::lround(dpi / 0.0254));
  std::string chunk = {0, 0, 0, 9, 'p', 'H', 'Y', 's'};
  for (int k = 0; k < 2; ++k)
    for (int b = 3; b >= 0; --b) chunk += static_cast<char>((ppm >> (8 * b)) & 0xff);
  chunk += static_cast<char>(1);  // unit: metre
  const uLong crc =
      crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(chunk.data() + 4), 13);
  for (int b = 3; b >= 0; --b) chunk += static_cast<char>((crc >> (8 * b)) & 0xff);
  png.insert(kAfterIhdr, chunk);
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(png.data(), static_cast<std::streamsize>(png.size()));
}

template <class F>
std::vector<std::string> Both(const std::string& base, F draw) {
  std::vector<std::string> files;
  // SVG and PDF in points (72 per inch), PNG at 300 dpi: the same figure, the same size in
  // inches.
  for (const auto& [dev, ext, dpi] :
       {std::tuple{"svgcairo", ".svg", 72.0}, std::tuple{"pngcairo", ".png", kPngDpi},
        std::tuple{"pdfcairo", ".pdf", 72.0}}) {
    Begin(dev, base + ext, dpi);
    draw(dpi);
    plend();
    if (std::string(ext) == ".png") SetPngDpi(base + ext, dpi);
    files.push_back(base + ext);
  }
  return files;
}

}  // namespace

std::vector<std::string> DrawBarChart(const BarChart& c, const std::string& base) {
  HL_REQUIRE(!c.groups.empty() && !c.series.empty(), "bar chart without data");
  return Both(base, [&](double) { DrawBars(c); });
}

std::vector<std::string> DrawLinePlot(const LinePlot& l, const std::string& base) {
  HL_REQUIRE(!l.x.empty() && !l.series.empty(), "line plot without data");
  auto files = Both(base, [&](double dpi) { DrawLines(l, dpi); });
  if (!l.note.empty()) DescribeSvg(base + ".svg", l.title, l.note);
  return files;
}

std::vector<std::string> DrawBoxPlot(const BoxPlot& b, const std::string& base) {
  HL_REQUIRE(b.groups.size() == b.samples.size() && !b.groups.empty(), "box plot without data");
  return Both(base, [&](double) { DrawBoxes(b); });
}

std::vector<std::string> DrawFigure(const std::string& base, const std::function<void()>& draw) {
  return Both(base, [&](double) { draw(); });
}

std::vector<std::string> DrawQqPlot(const QqPlot& q, const std::string& base) {
  HL_REQUIRE(q.sample.size() >= 3, "Q-Q plot of fewer than 3 values");
  return Both(base, [&](double) { DrawQq(q); });
}

}  // namespace hapticlab::stats
