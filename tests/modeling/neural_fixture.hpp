#pragma once
// Shared by the neural model tests (tests/modeling/neural*_test.cpp,
// tests/renderer/neural*_test.cpp): synthetic texture recordings that no project simulator
// produces, the quick fit options and a small trained model of each topology (fitted once per test
// executable).

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <numbers>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/modeling/neural.hpp"
#include "hapticlab/renderer/hybrid.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/renderer/vibration.hpp"

namespace hapticlab::modeling {
namespace {

constexpr double kPi = std::numbers::pi;  // NOLINT(misc-definitions-in-headers): internal

// A synthetic texture recording: a stylus dragged at v over a random surface whose profile
// has a dominant spatial period (a spatial AR(2) resonance at `period_m`), pressed with f.
// The tip follows the surface's curvature (temporal frequency v / period) through a contact
// resonance at 300 Hz; it cannot be pulled down harder than the load allows, so downward
// acceleration saturates at -c f (a nonlinearity that depends on the load).
inline Recording Texture(double v, double f, double period_m, std::uint64_t seed,
                         double seconds = 2.5) {
  const double fs = 5000, dx = 1e-6;
  Rng rng(seed);
  const std::size_t n = static_cast<std::size_t>(seconds * fs);
  const std::size_t len = static_cast<std::size_t>(v * seconds / dx) + 16;
  const double r = 0.995, th = 2 * kPi * dx / period_m;
  std::vector<double> h(len, 0.0);
  for (std::size_t i = 2; i < len; ++i)
    h[i] = 2 * r * std::cos(th) * h[i - 1] - r * r * h[i - 2] + 1e-8 * rng.Normal();
  auto z = [&](double x) {
    const double u = x / dx;
    const auto i = static_cast<std::size_t>(u);
    return h[i] + (h[i + 1] - h[i]) * (u - static_cast<double>(i));
  };
  const double dt = 1 / fs;
  // Tip resonance (300 Hz, Q 2) driven by the surface's acceleration.
  const double w0 = 2 * kPi * 300, zeta = 0.25;
  double y = 0, yd = 0;
  Recording rec;
  rec.speed_mps = v;
  rec.force_N = f;
  rec.rate_hz = fs;
  rec.file = fmt::format("texture v={} f={}", v, f);
  for (std::size_t k = 1; k + 1 < n; ++k) {
    const double t = static_cast<double>(k) * dt;
    const double a_s = (z(v * (t + dt)) - 2 * z(v * t) + z(v * (t - dt))) / (dt * dt);
    const double ydd = w0 * w0 * (a_s / (w0 * w0) - y) - 2 * zeta * w0 * yd;
    yd += ydd * dt;
    y += yd * dt;
    double a = std::max(ydd, -6.0 * f);  // lift-off: the load limits downward acceleration
    rec.acc.push_back(a + 0.01 * rng.Normal());
  }
  return rec;
}

inline std::vector<Recording> TextureGrid(double period_m, std::uint64_t seed) {
  std::vector<Recording> recs;
  int k = 0;
  for (const double v : {0.04, 0.06, 0.08, 0.10, 0.12})
    for (const double f : {0.54, 0.89, 1.18, 1.40, 1.91})
      recs.push_back(Texture(v, f, period_m, seed + static_cast<std::uint64_t>(k++)));
  return recs;
}

inline NeuralFitOptions Quick(renderer::NeuralTopology t) {
  NeuralFitOptions o;
  o.topology = t;
  o.train.max_epochs = 40;
  o.train.seed = 3;
  o.input_noise = 0.3;
  return o;
}

// The 2 x 2 corner grid of the thesis's training conditions (4, 12 cm/s x 0.54, 1.91 N), 1 s
// recordings of a 0.5 mm texture, data seeds from `first_seed`.
inline std::vector<Recording> CornerGrid(std::uint64_t first_seed) {
  std::vector<Recording> recs;
  std::uint64_t k = 0;
  for (const double v : {0.04, 0.12})
    for (const double f : {0.54, 1.91})
      recs.push_back(Texture(v, f, 0.5e-3, first_seed + k++, 1.0));
  return recs;
}

// The project's synthetic AR grid (tests/modeling/vibration_test.cpp): an AR(4) at 2 kHz whose
// two resonances move with speed and force, its variance growing with both. `nonlinear`
// adds a bounded bilinear term, 0.8 s tanh(x[k-1] / s) tanh(x[k-2] / s) with s the linear
// part's RMS: sum and difference frequencies of the resonances, a process no linear AR model
// is (and still stable: the term is bounded and the linear part is).
inline Recording ArGridRecording(double v, double f, bool nonlinear, std::uint64_t seed,
                                 double seconds = 2.5) {
  const double fs = 2000;
  const double f1 = 120 + 900 * v + 30 * f * f, f2 = 2.2 * f1;
  const double r1 = 0.97 - 0.02 * f, r2 = 0.9;
  auto poly = [&](double fr, double r) {
    return std::pair{2 * r * std::cos(2 * kPi * fr / fs), -r * r};
  };
  const auto [a1, a2] = poly(f1, r1);
  const auto [b1, b2] = poly(f2, r2);
  const double c[4] = {a1 + b1, a2 + b2 - a1 * b1, -a1 * b2 - a2 * b1, -a2 * b2};
  const double sd = std::sqrt(0.5 * std::pow(v / 0.08, 1.6) * (f / 1.2));
  Rng rng(seed);
  const std::size_t n = static_cast<std::size_t>(seconds * fs), warm = 2000;
  std::vector<double> x(n + warm, 0.0);
  // RMS of the linear process for unit excitation (to scale the nonlinearity's argument).
  double lin_rms = 1;
  if (nonlinear) {
    Rng r2n(seed + 999);
    std::vector<double> y(20000, 0.0);
    double ss = 0;
    for (std::size_t k = 4; k < y.size(); ++k) {
      y[k] = c[0] * y[k - 1] + c[1] * y[k - 2] + c[2] * y[k - 3] + c[3] * y[k - 4] + r2n.Normal();
      ss += y[k] * y[k];
    }
    lin_rms = std::sqrt(ss / static_cast<double>(y.size()));
  }
  for (std::size_t k = 4; k < x.size(); ++k) {
    double a = c[0] * x[k - 1] + c[1] * x[k - 2] + c[2] * x[k - 3] + c[3] * x[k - 4] + rng.Normal();
    if (nonlinear)
      a += 0.8 * lin_rms * std::tanh(x[k - 1] / lin_rms) * std::tanh(x[k - 2] / lin_rms);
    x[k] = a;
  }
  Recording rec;
  rec.speed_mps = v;
  rec.force_N = f;
  rec.rate_hz = fs;
  rec.file = fmt::format("{} AR v={} f={}", nonlinear ? "nonlinear" : "linear", v, f);
  for (std::size_t k = warm; k < x.size(); ++k) rec.acc.push_back(sd * x[k]);
  return rec;
}

// A small trained model (fast): the training grid of the thesis, short recordings. `cell_ar`:
// Γ_U with per-cell AR fits as its linear part (its fallback, forced by a radius limit of 0).
inline const renderer::NeuralModel& SmallModel(renderer::NeuralTopology t, bool cell_ar = false) {
  static const auto kMake = [](renderer::NeuralTopology topo, bool per_cell) {
    const auto recs = CornerGrid(50);
    NeuralFitOptions o = Quick(topo);
    o.train.max_epochs = 5;
    o.hidden_large = {8, 4};
    o.hidden_small = {6};
    for (auto& b : o.bands) b.history = 12;
    if (per_cell) o.max_condition_basis_radius = 0;
    return FitNeural(recs, o);
  };
  static const auto kUnified = kMake(renderer::NeuralTopology::kUnified, false),
                    kDecomposed = kMake(renderer::NeuralTopology::kDecomposed, false);
  if (cell_ar) {
    static const auto kUnifiedPerCell = kMake(renderer::NeuralTopology::kUnified, true);
    return kUnifiedPerCell;
  }
  return t == renderer::NeuralTopology::kUnified ? kUnified : kDecomposed;
}
}  // namespace
}  // namespace hapticlab::modeling
