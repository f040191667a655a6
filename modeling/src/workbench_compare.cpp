// Workbench `compare`: errors overall and residuals binned by regime, speed, load, direction,
// position, time and frequency band.

#include "hapticlab/modeling/workbench_compare.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "workbench_internal.hpp"

namespace hapticlab::modeling::wb {

using namespace internal;  // NOLINT(google-build-using-namespace): the workbench's own kernels

// ---------------------------------------------------------------------------------------------
namespace {

struct Dim {
  std::string name;
  std::vector<double> edges;
  std::vector<std::string> labels;
};

std::vector<BinRow> Bin(const Dim& d, const std::vector<double>& key,
                        const std::vector<double>& val, const std::vector<char>& use) {
  std::vector<BinRow> rows(d.edges.size() - 1);
  for (std::size_t j = 0; j + 1 < d.edges.size(); ++j) {
    rows[j].label =
        d.labels.empty() ? fmt::format("{:g}-{:g}", d.edges[j], d.edges[j + 1]) : d.labels[j];
    rows[j].center = std::isfinite(d.edges[j + 1]) ? (d.edges[j] + d.edges[j + 1]) / 2 : d.edges[j];
  }
  for (std::size_t i = 0; i < key.size(); ++i) {
    if (!use[i]) continue;
    for (std::size_t j = 0; j + 1 < d.edges.size(); ++j)
      if (key[i] >= d.edges[j] && key[i] < d.edges[j + 1]) {
        rows[j].mean += val[i];
        rows[j].rms += val[i] * val[i];
        ++rows[j].n;
        break;
      }
  }
  for (auto& r : rows)
    if (r.n) r.mean /= r.n, r.rms = std::sqrt(r.rms / r.n);
  return rows;
}

// Each force sample's bin keys (speed in mm/s, load, direction with +180 wrapped to the first
// bin, tile of the 3 x 3 grid, time in tenths of the recording, regime) and which samples each
// channel's residual is binned over.
struct SampleKeys {
  std::vector<double> speed_mm, load, dir, tile, time, regime;
  std::vector<char> contact, sliding, moving;
};
SampleKeys KeysOf(const Replay& r, double T0, double T1) {
  const std::size_t n = r.samples().size();
  const double pi = std::numbers::pi;
  SampleKeys k;
  for (auto* v : {&k.speed_mm, &k.load, &k.dir, &k.tile, &k.time, &k.regime}) v->resize(n);
  for (auto* v : {&k.contact, &k.sliding, &k.moving}) v->resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& s = r.samples()[i];
    k.speed_mm[i] = s.speed_mps * 1e3;
    k.load[i] = s.fn_N;
    k.dir[i] = s.dir_rad;
    const int tx = std::clamp(
        static_cast<int>(3 * (s.x_m - r.x_min) / std::max(r.x_max - r.x_min, 1e-9)), 0, 2);
    const int ty = std::clamp(
        static_cast<int>(3 * (s.y_m - r.y_min) / std::max(r.y_max - r.y_min, 1e-9)), 0, 2);
    k.tile[i] = 3 * ty + tx;
    k.time[i] = (s.t_s - T0) / (T1 - T0) * 10;
    k.regime[i] =
        s.speed_mps <= kPreslidingSpeed_mps ? 0 : (s.speed_mps < kSlidingSpeed_mps ? 1 : 2);
    k.contact[i] = s.contact;
    k.sliding[i] = s.contact && s.speed_mps >= kSlidingSpeed_mps;
    k.moving[i] =
        s.contact && s.speed_mps >= kPreslidingSpeed_mps;  // friction along the motion is defined
  }
  // Directions near +180 belong to the first bin (-180).
  for (auto& d : k.dir)
    if (d >= pi - pi / 8) d -= 2 * pi;
  return k;
}

// The dimensions a residual is binned by: regime, speed, load, direction, position, time.
std::vector<Dim> Dims() {
  const double inf = std::numeric_limits<double>::infinity(), pi = std::numbers::pi;
  std::vector<double> dir_edges;
  std::vector<std::string> dir_labels;
  for (int k = 0; k <= 8; ++k) dir_edges.push_back(-pi + k * pi / 4 - pi / 8);
  for (int k = 0; k < 8; ++k) dir_labels.push_back(fmt::format("{:.0f} deg", -180 + 45.0 * k));
  return {
      {"regime",
       {0, 1, 2, 3},
       {"pre-sliding (<= 0.5 mm/s)", "transition (0.5-3 mm/s)", "sliding (>= 3 mm/s)"}},
      {"speed", {0, 0.5, 3, 10, 30, 60, 100, 150, inf}, {}},
      {"load", {0, 0.5, 1, 1.5, 2, 3, inf}, {}},
      {"direction", dir_edges, dir_labels},
      {"position",
       {0, 1, 2, 3, 4, 5, 6, 7, 8, 9},
       {"front-left", "front-centre", "front-right", "middle-left", "centre", "middle-right",
        "back-left", "back-centre", "back-right"}},
      {"time", {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10}, {}},
  };
}

// The vibration residual (dB): per frequency band over the windows, and each window's mean over
// the bands binned by speed, load, direction and time (dims as Dims()).
void AddVibrationBreakdown(const Replay& r, const Residuals& res, const std::vector<Dim>& dims,
                           double T0, double T1, Comparison* c) {
  const double pi = std::numbers::pi;
  const std::size_t nw = r.windows.size(), nb = r.band_lo_hz.size();
  const double db = 10 / std::log(10.0);
  // Per band: residual in dB over the windows.
  for (std::size_t b = 0; b < nb; ++b) {
    BinRow row;
    row.label = fmt::format("{:.0f}-{:.0f} Hz", r.band_lo_hz[b], r.band_hi_hz[b]);
    row.center = std::sqrt(r.band_lo_hz[b] * r.band_hi_hz[b]);
    for (std::size_t w = 0; w < nw; ++w) {
      const double x = res.log_band[w][b] * db;
      row.mean += x, row.rms += x * x, ++row.n;
    }
    if (row.n) row.mean /= row.n, row.rms = std::sqrt(row.rms / row.n);
    c->breakdown["band"]["vibration_dB"].push_back(row);
  }
  std::vector<double> wspeed(nw), wload(nw), wdir(nw), wtime(nw), wres(nw);
  std::vector<char> all(nw, 1);
  for (std::size_t w = 0; w < nw; ++w) {
    wspeed[w] = r.windows[w].speed_mps * 1e3;
    wload[w] = r.windows[w].force_N;
    wdir[w] = std::atan2(r.windows[w].dir[1], r.windows[w].dir[0]);
    if (wdir[w] >= pi - pi / 8) wdir[w] -= 2 * pi;
    wtime[w] = (r.windows[w].t_s - T0) / (T1 - T0) * 10;
    double s = 0;
    for (const double x : res.log_band[w]) s += x;
    wres[w] = s / static_cast<double>(nb) * db;
  }
  c->breakdown["speed"]["vibration_dB"] = Bin(dims[1], wspeed, wres, all);
  c->breakdown["load"]["vibration_dB"] = Bin(dims[2], wload, wres, all);
  c->breakdown["direction"]["vibration_dB"] = Bin(dims[3], wdir, wres, all);
  c->breakdown["time"]["vibration_dB"] = Bin(dims[5], wtime, wres, all);
}

}  // namespace

Comparison Compare(const Model& m, const Replay& r) {
  Comparison c;
  const auto p = Predict(m, r);
  c.errors = ComputeErrors(r, p, Split::kAll);
  const auto res = ComputeResiduals(m, r, p);
  const double T0 = r.samples().front().t_s, T1 = r.samples().back().t_s + 1e-9;
  const SampleKeys k = KeysOf(r, T0, T1);
  const std::vector<Dim> dims = Dims();
  const std::vector<const std::vector<double>*> keys = {&k.regime, &k.speed_mm, &k.load,
                                                        &k.dir,    &k.tile,     &k.time};
  for (std::size_t d = 0; d < dims.size(); ++d) {
    c.breakdown[dims[d].name]["normal_force_N"] = Bin(dims[d], *keys[d], res.normal_N, k.contact);
    c.breakdown[dims[d].name]["friction_N"] =
        Bin(dims[d], *keys[d], res.friction_N, d <= 1 ? k.moving : k.sliding);
    if (d != 0)
      c.breakdown[dims[d].name]["friction_ratio"] = Bin(dims[d], *keys[d], res.ratio, k.sliding);
  }
  if (!res.log_band.empty()) AddVibrationBreakdown(r, res, dims, T0, T1, &c);
  return c;
}

}  // namespace hapticlab::modeling::wb
