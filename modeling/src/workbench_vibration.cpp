// The workbench scores vibration models it does not fit: AR banks and neural models
// (workbench_vibration.hpp).

#include "hapticlab/modeling/workbench_vibration.hpp"

#include <fmt/format.h>

#include <cmath>
#include <complex>
#include <map>
#include <mutex>
#include <numbers>
#include <utility>

#include "hapticlab/modeling/neural.hpp"
#include "hapticlab/modeling/vibration.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/renderer/neural.hpp"
#include "hapticlab/renderer/vibration.hpp"
#include "workbench_internal.hpp"

namespace hapticlab::modeling::wb {
namespace {

// Per-sample power spectrum of the interpolated AR(MA) filter at frequency f [Hz] of a model
// running at `rate`: gain^2 sigma^2 |1 + sum b_j z^-j|^2 / |1 - sum c_i z^-i|^2, z = e^{i w}.
double FilterSpectrum(const renderer::ArFilter& flt, double f, double rate) {
  const double w = 2 * std::numbers::pi * f / rate;
  std::complex<double> a(1, 0), b(1, 0);
  for (int i = 0; i < flt.order; ++i) a -= flt.c[i] * std::polar(1.0, -w * (i + 1));
  for (int j = 0; j < flt.ma_order; ++j) b += flt.b[j] * std::polar(1.0, -w * (j + 1));
  return flt.gain * flt.gain * flt.sigma * flt.sigma * std::norm(b) / std::norm(a);
}

// Welch estimate (Hann, 512-sample segments, half overlap) of a signal's per-sample power
// spectrum at bins 0..256 of the segment: the squared Welch magnitudes E_s compares
// (WelchMagnitude, vibration.hpp) divided by the window's energy sum(w^2).
std::vector<double> Welch(const std::vector<double>& x) {
  constexpr int kSeg = 512;
  double wss = 0;
  for (int k = 0; k < kSeg; ++k) {
    const double w = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * k / kSeg);
    wss += w * w;
  }
  std::vector<double> psd = WelchMagnitude(x, kSeg);
  for (auto& v : psd) v = v * v / wss;
  return psd;
}

// A Welch spectrum (per-sample, at `rate`) read at frequency f by linear interpolation.
double AtFrequency(const std::vector<double>& psd, double f, double rate) {
  const double k = f / rate * 2 * static_cast<double>(psd.size() - 1);
  const auto k0 =
      static_cast<std::size_t>(std::clamp(std::floor(k), 0.0, static_cast<double>(psd.size() - 2)));
  const double a = std::clamp(k - static_cast<double>(k0), 0.0, 1.0);
  return (1 - a) * psd[k0] + a * psd[k0 + 1];
}

double ModelRate(const renderer::MaterialModel& vm) {
  return vm.neural ? vm.neural->sample_rate_hz : vm.vibration.sample_rate_hz;
}

}  // namespace

std::string AttachVibrationModel(Model* m, const std::string& path) {
  if (m->HasVibration()) return "";
  auto mat = std::make_shared<renderer::MaterialModel>(renderer::LoadMaterial(path));
  std::string what;
  if (mat->neural) {
    what = fmt::format(
        "a neural model ({}, {:.0f} Hz{})",
        mat->neural->topology == renderer::NeuralTopology::kUnified ? "unified" : "decomposed",
        mat->neural->sample_rate_hz, mat->neural->calibrated ? "" : ", uncalibrated");
  } else if (!mat->vibration.empty()) {
    what = fmt::format("an {} bank ({} cells, order {}, {:.0f} Hz)",
                       mat->vibration.cells.front().ma.empty() ? "AR" : "ARMA",
                       mat->vibration.cells.size(), mat->vibration.order(),
                       mat->vibration.sample_rate_hz);
  } else {
    return "";
  }
  m->vibration_model = std::move(mat);
  m->vibration_spectra = std::make_shared<VibrationSpectra>();
  return what;
}

double VibrationModelTopHz(const renderer::MaterialModel& vm) { return 0.45 * ModelRate(vm); }

std::vector<std::vector<double>> PredictModelBands(const renderer::MaterialModel& vm,
                                                   const Replay& r, VibrationSpectra* cache) {
  std::vector<std::vector<double>> out;
  if (r.windows.empty()) return out;
  const double fs_model = ModelRate(vm), fs_meas = r.acc_rate_hz;
  const int n = r.windows.front().rows;
  const auto bins = internal::BandBins(r, n, fs_meas);
  // The model's spectrum at a condition, as a function of frequency [Hz], per sample of the
  // model; a band's power is its mean over the band's bins, converted to the measurement's
  // per-bin units by fs_meas / fs_model (the same continuous density at either rate).
  auto bands_of = [&](const auto& spectrum) {
    std::vector<double> bp(bins.size());
    for (std::size_t b = 0; b < bins.size(); ++b) {
      double s = 0;
      for (const int k : bins[b]) s += spectrum(k * fs_meas / n);
      bp[b] = std::max(s / static_cast<double>(bins[b].size()) * fs_meas / fs_model, 1e-300);
    }
    return bp;
  };
  if (!vm.neural) {
    renderer::VibrationInterpolator interp(vm.vibration);
    renderer::ArFilter flt;
    for (const auto& w : r.windows) {
      // A window slower than the bank's switch-off speed is scored at that speed.
      interp.Interpolate(std::max(w.speed_mps, vm.vibration.min_speed_mps), w.force_N, true, &flt);
      out.push_back(bands_of([&](double f) { return FilterSpectrum(flt, f, fs_model); }));
    }
    return out;
  }
  // Neural: one synthesis per condition rounded to 5 % steps (windows of a steady scan share it).
  VibrationSpectra local;
  VibrationSpectra& spectra = cache ? *cache : local;
  const std::lock_guard<std::mutex> lock(spectra.mu);
  const double step = std::log(1.05);
  for (const auto& w : r.windows) {
    const std::pair<long, long> key{std::lround(std::log(w.speed_mps) / step),
                                    std::lround(std::log(std::max(w.force_N, 1e-3)) / step)};
    auto it = spectra.by_condition.find(key);
    if (it == spectra.by_condition.end()) {
      const double v = std::max(std::exp(static_cast<double>(key.first) * step),
                                vm.neural->min_speed_mps),
                   f = std::exp(static_cast<double>(key.second) * step);
      it = spectra.by_condition.emplace(key, Welch(SynthesizeNeural(*vm.neural, v, f, 16384, 1)))
               .first;
    }
    const auto& psd = it->second;
    out.push_back(bands_of([&](double f) { return AtFrequency(psd, f, fs_model); }));
  }
  return out;
}

std::vector<EsCell> VibrationEsByCondition(const Replay& r, const Prediction& p, Split split) {
  std::vector<EsCell> out;
  if (p.band_power.empty()) return out;
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<double> sp = {0.01, 0.03, 0.06, 0.1, 0.15, inf};
  const std::vector<double> fo = {0, 0.5, 1, 1.5, 2, 3, inf};
  auto index = [](const std::vector<double>& e, double x) {
    for (std::size_t j = 0; j + 1 < e.size(); ++j)
      if (x >= e[j] && x < e[j + 1]) return static_cast<int>(j);
    return x < e.front() ? 0 : static_cast<int>(e.size()) - 2;
  };
  std::map<std::pair<int, int>, std::pair<int, double>> acc;
  for (std::size_t w = 0; w < r.windows.size() && w < p.band_power.size(); ++w) {
    if (!internal::InSplit(r.windows[w].block, split)) continue;
    auto& a = acc[{index(sp, r.windows[w].speed_mps), index(fo, r.windows[w].force_N)}];
    a.first += 1;
    a.second += internal::WindowEs(r.windows[w].band_power, p.band_power[w]);
  }
  auto edge = [](double x, double scale) {
    return std::isfinite(x) ? fmt::format("{:g}", x * scale) : std::string();
  };
  for (const auto& [k, a] : acc) {
    EsCell c{
        sp[k.first], sp[k.first + 1], fo[k.second], fo[k.second + 1], a.first, a.second / a.first,
        ""};
    const std::string s_hi = edge(c.speed_hi_mps, 1e3), f_hi = edge(c.force_hi_N, 1);
    c.label = fmt::format(
        "{} mm/s, {} N",
        s_hi.empty() ? ">= " + edge(c.speed_lo_mps, 1e3) : edge(c.speed_lo_mps, 1e3) + "-" + s_hi,
        f_hi.empty() ? ">= " + edge(c.force_lo_N, 1) : edge(c.force_lo_N, 1) + "-" + f_hi);
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace hapticlab::modeling::wb
