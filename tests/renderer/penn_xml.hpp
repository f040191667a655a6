#pragma once
// Model sets in the Penn Haptic Texture Toolkit's XML schema, generated here (the toolkit's
// own files may not be redistributed), and an independent reference of how the toolkit
// renders them: its documented semantics (AccSynthHashMatrix: saturation at maxSpeed/maxForce,
// barycentric weights in the file's triangles, LSFs, variance and gain mixed linearly) and
// the analytic AR/ARMA power spectral density of the mixed model.

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <string>
#include <vector>

#include "hapticlab/renderer/ar.hpp"

namespace hapticlab::test {

struct PennModelSpec {
  double speed_mmps = 0, force_N = 0;
  std::vector<double> lsf;     // AR LSFs [rad/sample], as written (6 decimals)
  std::vector<double> ma_lsf;  // MA LSFs (ARMA only)
  double var = 0;              // excitation variance
  double gain = 1;             // ARMA gain
};

struct PennSetSpec {
  std::string material = "Generated Cloth";
  double rate_hz = 10000;
  double max_speed_mmps = 0, max_force_N = 0;  // 0: not written
  std::vector<PennModelSpec> models;
  std::vector<std::array<int, 3>> tri;  // 0-based here; written 1-based
  int p = 0, q = 0;                     // AR order, MA order (0: AR set)
};

inline double Round6(double x) { return std::round(x * 1e6) / 1e6; }

// Scattered vertices over [0, 250] mm/s x [0, 2.5] N. Speed-0 and force-0 vertices are the
// toolkit's boundary models (var = 0); the others carry a resonance that moves with speed
// and force, a variance growing with both, and (ARMA) zeros and a gain that move too.
// `tri` is a valid triangulation of these vertices, hand-made (0-based).
inline PennSetSpec MakePennSet(bool arma) {
  PennSetSpec s;
  s.rate_hz = arma ? 1000 : 10000;
  s.p = arma ? 6 : 10;
  s.q = arma ? 2 : 0;
  s.max_speed_mmps = 250;
  s.max_force_N = 2.5;
  s.material = arma ? "Generated Cloth ARMA" : "Generated Cloth AR";
  const double v[][2] = {
      {0, 0},    {0, 1.2},   {0, 2.5},   {120, 0},   {250, 0},               // boundary: var = 0
      {60, 0.7}, {170, 0.9}, {110, 1.8}, {250, 1.3}, {160, 2.5}, {250, 2.5}  // measured
  };
  for (int i = 0; i < 11; ++i) {
    PennModelSpec m;
    m.speed_mmps = v[i][0];
    m.force_N = v[i][1];
    const bool boundary = m.speed_mmps == 0 || m.force_N == 0;
    // Evenly spread LSFs with the first pair pulled around a resonance f_r.
    const double fr_hz =
        arma ? 60 + 0.3 * m.speed_mmps + 20 * m.force_N : 150 + 2 * m.speed_mmps + 150 * m.force_N;
    const double wr = 2 * std::numbers::pi * fr_hz / s.rate_hz, half_gap = arma ? 0.12 : 0.06;
    for (int k = 0; k < s.p; ++k) m.lsf.push_back((k + 1) * std::numbers::pi / (s.p + 1));
    m.lsf[0] = wr - half_gap;
    m.lsf[1] = wr + half_gap;
    for (auto& x : m.lsf) x = Round6(x);
    if (arma) {
      m.ma_lsf = {Round6(1.6 + 0.1 * m.force_N), Round6(2.6 - 0.001 * m.speed_mmps)};
      m.gain = Round6(2.0 + 0.01 * m.speed_mmps + m.force_N);
      m.var = boundary ? 0.0 : Round6(1e-3 * (1 + m.speed_mmps / 50) * (0.5 + m.force_N));
    } else {
      m.var = boundary ? 0.0 : Round6(1e-4 * (1 + m.speed_mmps / 50) * (0.5 + m.force_N));
    }
    s.models.push_back(m);
  }
  // Vertices: 0 (0,0) 1 (0,1.2) 2 (0,2.5) 3 (120,0) 4 (250,0) 5 (60,0.7) 6 (170,0.9)
  //           7 (110,1.8) 8 (250,1.3) 9 (160,2.5) 10 (250,2.5)
  s.tri = {{0, 3, 5}, {0, 5, 1}, {3, 6, 5}, {3, 4, 6}, {4, 8, 6}, {5, 6, 7},
           {1, 5, 7}, {1, 7, 2}, {2, 7, 9}, {6, 8, 7}, {7, 8, 9}, {8, 10, 9}};
  return s;
}

inline std::string PennXml(const PennSetSpec& s) {
  auto values = [](const std::vector<double>& v, const char* f) {
    std::string o;
    for (double x : v)
      o += fmt::format(fmt::runtime(std::string("      <value>") + f + "</value>\n"), x);
    return o;
  };
  std::string x = "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<modelSet texture=\"1\">\n";
  x += fmt::format(
      "   <material>{}</material>\n   <SampleRate>{:g}</SampleRate>\n   <mu>0.35</mu>\n",
      s.material, s.rate_hz);
  x += fmt::format("   <numMod>{}</numMod>\n   <numTri>{}</numTri>\n", s.models.size(),
                   s.tri.size());
  if (s.max_speed_mmps > 0) x += fmt::format("   <maxSpeed>{:.6f}</maxSpeed>\n", s.max_speed_mmps);
  if (s.max_force_N > 0) x += fmt::format("   <maxForce>{:.6f}</maxForce>\n", s.max_force_N);
  std::vector<double> sp, fo;
  for (const auto& m : s.models) {
    sp.push_back(m.speed_mmps);
    fo.push_back(m.force_N);
  }
  x += "   <speedList type=\"array\">\n" + values(sp, "{:.6f}") + "   </speedList>\n";
  x += "   <forceList type=\"array\">\n" + values(fo, "{:.6f}") + "   </forceList>\n";
  for (const auto& t : s.tri)
    x += fmt::format(
        "   <tri type=\"array\">\n      <value>{}</value>\n      <value>{}</value>\n      "
        "<value>{}</value>\n   </tri>\n",
        t[0] + 1, t[1] + 1, t[2] + 1);
  x += fmt::format("   <numARCoeff>{}</numARCoeff>\n", s.p);
  if (s.q > 0) x += fmt::format("   <numMACoeff>{}</numMACoeff>\n", s.q);
  for (std::size_t i = 0; i < s.models.size(); ++i) {
    const auto& m = s.models[i];
    std::vector<double> a{1.0};
    for (double c : renderer::LsfToAr(m.lsf)) a.push_back(-c);
    x += fmt::format("   <model>\n      <modNum>{}</modNum>\n      <ARcoeff>\n", i + 1);
    x += values(a, "{:.17g}") + "      </ARcoeff>\n      <ARlsf>\n" + values(m.lsf, "{:.6f}") +
         "      </ARlsf>\n";
    if (s.q > 0) {
      std::vector<double> b{1.0};
      for (double c : renderer::LsfToAr(m.ma_lsf)) b.push_back(-c);
      x += "      <MAcoeff>\n" + values(b, "{:.17g}") + "      </MAcoeff>\n      <MAlsf>\n" +
           values(m.ma_lsf, "{:.6f}") + "      </MAlsf>\n";
      x += fmt::format("      <gain>{:.6f}</gain>\n", m.gain);
    }
    x += fmt::format("      <var>{:.6f}</var>\n", m.var);
    x += fmt::format(
        "      <speedMod>{:.6f}</speedMod>\n      <forceMod>{:.6f}</forceMod>\n   </model>\n",
        m.speed_mmps, m.force_N);
  }
  return x + "</modelSet>\n";
}

// The model the toolkit plays at (speed, force): saturated as HashAndInterp2 does (and, with
// `light_load_rule`, a force below 0.05 N taken as 1e-4 N, its "essentially zero"), weights
// from the file's triangle containing the point, LSFs, variance and gain mixed linearly.
struct PennReference {
  std::vector<double> c, b;  // AR c_1..c_p (a[k] = sum c_i a[k-i] + ...), MA b_1..b_q
  double var = 0, gain = 1, rate_hz = 0;
  bool arma = false;
  // One-sided PSD [(m/s^2)^2/Hz]: 2 var gain^2 |B|^2 / (fs |A|^2), below the model's Nyquist.
  double Psd(double f_hz) const {
    const double w = 2 * std::numbers::pi * f_hz / rate_hz;
    std::complex<double> a(1, 0), bb(1, 0);
    for (std::size_t i = 0; i < c.size(); ++i)
      a -= c[i] * std::polar(1.0, -w * static_cast<double>(i + 1));
    for (std::size_t j = 0; j < b.size(); ++j)
      bb += b[j] * std::polar(1.0, -w * static_cast<double>(j + 1));
    const double g = arma ? gain : 1.0;
    return 2 * var * g * g * std::norm(bb) / (rate_hz * std::norm(a));
  }
  // Mean PSD over [lo, hi] and the total power up to the model's Nyquist (fine midpoint sums).
  double MeanPsd(double lo, double hi) const {
    const int n = 2000;
    double s = 0;
    for (int i = 0; i < n; ++i) s += Psd(lo + (hi - lo) * (i + 0.5) / n);
    return s / n;
  }
  double Power() const { return MeanPsd(0, 0.5 * rate_hz) * 0.5 * rate_hz; }
};

inline PennReference PennExpected(const PennSetSpec& s, double speed_mmps, double force_N,
                                  bool light_load_rule = true) {
  if (speed_mmps > s.max_speed_mmps) speed_mmps = s.max_speed_mmps - 0.01;
  if (force_N > s.max_force_N)
    force_N = s.max_force_N - 0.01;
  else if (light_load_rule && force_N < 0.05)
    force_N = 1e-4;
  PennReference r;
  r.rate_hz = s.rate_hz;
  r.arma = s.q > 0;
  for (const auto& t : s.tri) {
    const auto& A = s.models[static_cast<std::size_t>(t[0])];
    const auto& B = s.models[static_cast<std::size_t>(t[1])];
    const auto& C = s.models[static_cast<std::size_t>(t[2])];
    const double det = (B.force_N - C.force_N) * (A.speed_mmps - C.speed_mmps) +
                       (C.speed_mmps - B.speed_mmps) * (A.force_N - C.force_N);
    const double w1 = ((B.force_N - C.force_N) * (speed_mmps - C.speed_mmps) +
                       (C.speed_mmps - B.speed_mmps) * (force_N - C.force_N)) /
                      det;
    const double w2 = ((C.force_N - A.force_N) * (speed_mmps - C.speed_mmps) +
                       (A.speed_mmps - C.speed_mmps) * (force_N - C.force_N)) /
                      det;
    const double w3 = 1 - w1 - w2;
    if (w1 < -1e-12 || w2 < -1e-12 || w3 < -1e-12) continue;
    const PennModelSpec* m[3] = {&A, &B, &C};
    const double w[3] = {w1, w2, w3};
    std::vector<double> lsf(A.lsf.size(), 0.0), ma(A.ma_lsf.size(), 0.0);
    r.gain = 0;
    for (int k = 0; k < 3; ++k) {
      for (std::size_t i = 0; i < lsf.size(); ++i) lsf[i] += w[k] * m[k]->lsf[i];
      for (std::size_t i = 0; i < ma.size(); ++i) ma[i] += w[k] * m[k]->ma_lsf[i];
      r.var += w[k] * m[k]->var;
      r.gain += w[k] * m[k]->gain;
    }
    r.c = renderer::LsfToAr(lsf);
    for (double x : renderer::LsfToAr(ma)) r.b.push_back(-x);
    return r;
  }
  throw std::logic_error(
      fmt::format("({}, {}) is outside the generated set's triangles", speed_mmps, force_N));
}

}  // namespace hapticlab::test
