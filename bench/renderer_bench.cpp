// Cost of the renderer's real-time ticks.
//  - ForceTickFric2Hybrid2048: one force tick, fric2, hybrid low-pass, 2048 x 2048 height map,
//    the tool stroking at 5 cm/s (new cache lines of the map as it goes), including the
//    vibration filter update (LSF interpolation of an order-20 bank) the tick publishes.
//  - VibrationSampleAr20: one vibration sample, order-20 AR, high-pass, with the filter
//    updated by a force tick every 10 samples (a 1 kHz force loop under a 10 kHz vibration
//    loop); the force tick's own cost is excluded with manual timing.
//
//  - NeuralSample{Unified,Decomposed}: one model-rate (2 kHz) sample of the neural model
//    (ch. III.3) with the thesis's network sizes (4 bands, M = 50, 30-25-15-5 / 30-15-5);
//    Γ_D on a 3 x 3 grid interpolates four networks per band.
//  - VibrationTickNeural{Unified,Decomposed}: one 10 kHz vibration-loop tick of the hybrid
//    renderer playing the neural model (a model sample every 5 ticks, high-pass included).
//
//   build/bench/renderer_bench [--benchmark_repetitions=5 --benchmark_report_aggregates_only=true]

#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <random>

#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/hybrid.hpp"
#include "hapticlab/renderer/neural.hpp"

namespace {

using namespace hapticlab::renderer;

MaterialModel BenchMaterial(int map_size, int order) {
  MaterialModel m;
  m.contact.texture = {800, 2, 1.2};
  m.contact.base = {1500, 0, 1};
  m.contact.layer_thickness_m = 0.5e-3;
  m.friction = {2500, 0.35, 0.4};
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<float> u(0.f, 40e-6f);
  std::vector<float> h(static_cast<std::size_t>(map_size) * static_cast<std::size_t>(map_size));
  for (auto& x : h) x = u(rng);
  m.geometry = std::make_shared<HeightMap>(map_size, map_size, 10e-6, std::move(h));
  VibrationBank& b = m.vibration;
  b.sample_rate_hz = 2000;
  b.grid_speeds_mps = {0.04, 0.08, 0.12};
  b.grid_forces_N = {0.54, 1.18, 1.91};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      ArCell c;
      c.speed_mps = b.grid_speeds_mps[static_cast<std::size_t>(i)];
      c.force_N = b.grid_forces_N[static_cast<std::size_t>(j)];
      for (int k = 0; k < order; ++k)
        c.lsf.push_back((k + 0.6 + 0.1 * i + 0.05 * j) * 3.0 / (order + 1));
      c.coeffs = LsfToAr(c.lsf);
      c.variance = 1.0;
      b.cells.push_back(c);
    }
  return m;
}

DeviceSample Stroke(std::int64_t k, double rate) {
  DeviceSample s;
  const double t = static_cast<double>(k) / rate;
  // A circle of 8 mm radius at 5 cm/s, 0.3 mm into the layer: speed and load vary little.
  const double w = 0.05 / 8e-3;
  s.state.p_m = {8e-3 * std::cos(w * t) + 10e-3, 8e-3 * std::sin(w * t) + 10e-3, 0.2e-3};
  s.state.v_mps = {-0.05 * std::sin(w * t), 0.05 * std::cos(w * t), 0};
  s.t_s = t;
  return s;
}

void ForceTickFric2Hybrid2048(benchmark::State& state) {
  const auto m = BenchMaterial(2048, 20);
  RenderOptions o;
  o.algorithm = ForceAlgorithm::kFric2;
  o.hybrid_filter = true;
  HybridRenderer r(m, o);
  std::int64_t k = 0;
  for (auto _ : state) {
    const auto s = Stroke(k, o.force_rate_hz);
    benchmark::DoNotOptimize(r.ForceTick(s, s.t_s));
    ++k;
  }
}
BENCHMARK(ForceTickFric2Hybrid2048);

// Vibration ticks at 10 kHz with a force tick (untimed) every 10th, as a 1 kHz loop gives.
void VibrationTicks(benchmark::State& state, const MaterialModel& m) {
  RenderOptions o;
  HybridRenderer r(m, o);
  std::int64_t k = 0;
  for (auto _ : state) {
    if (k % 10 == 0) {
      state.PauseTiming();
      const auto s = Stroke(k / 10, o.force_rate_hz);
      r.ForceTick(s, s.t_s);
      state.ResumeTiming();
    }
    benchmark::DoNotOptimize(r.VibrationTick());
    ++k;
  }
}
void VibrationSampleAr20(benchmark::State& state) { VibrationTicks(state, BenchMaterial(64, 20)); }
BENCHMARK(VibrationSampleAr20);

// The LSF -> AR filter update alone (runs once per force tick, inside ForceTick above).
void VibrationFilterUpdateAr20(benchmark::State& state) {
  const auto m = BenchMaterial(64, 20);
  VibrationInterpolator interp(m.vibration);
  ArFilter f;
  double v = 0.04;
  for (auto _ : state) {
    interp.Interpolate(v, 1.0, true, &f);
    v = v > 0.11 ? 0.04 : v + 1e-4;
    benchmark::DoNotOptimize(f);
  }
}
BENCHMARK(VibrationFilterUpdateAr20);

// A neural model with the thesis's sizes and random (Glorot) weights: the cost does not depend
// on the trained values.
std::shared_ptr<NeuralModel> BenchNeural(NeuralTopology t) {
  auto m = std::make_shared<NeuralModel>();
  m->topology = t;
  m->speeds_mps = {0.04, 0.08, 0.12};
  m->forces_N = {0.54, 1.18, 1.91};
  m->bands = DefaultNeuralBands();
  std::mt19937_64 rng(3);
  for (std::size_t b = 0; b < m->bands.size(); ++b) {
    auto& band = m->bands[b];
    const bool large = t == NeuralTopology::kUnified || b == 0;
    std::vector<int> layers{band.history + (t == NeuralTopology::kUnified ? 2 : 0)};
    for (const int h : large ? std::vector<int>{30, 25, 15, 5} : std::vector<int>{30, 15, 5})
      layers.push_back(h);
    layers.push_back(1);
    const std::size_t nets = t == NeuralTopology::kUnified ? 1 : 9;
    for (std::size_t k = 0; k < nets; ++k) {
      NeuralNet n{layers, {}};
      for (std::size_t l = 0; l + 1 < layers.size(); ++l) {
        const double a = std::sqrt(6.0 / (layers[l] + layers[l + 1]));
        std::uniform_real_distribution<double> u(-a, a);
        for (int i = 0; i < layers[l + 1] * layers[l]; ++i) n.params.push_back(u(rng));
        for (int i = 0; i < layers[l + 1]; ++i) n.params.push_back(0.0);
      }
      band.nets.push_back(std::move(n));
    }
    band.sigma.assign(9, 0.3);
    band.scale = 1;
  }
  return m;
}

void NeuralSample(benchmark::State& state, NeuralTopology t) {
  NeuralSynth s(BenchNeural(t), 1);
  double v = 0.05;
  for (auto _ : state) {
    benchmark::DoNotOptimize(s.Step(v, 1.0, true));
    v = v > 0.11 ? 0.05 : v + 1e-6;
  }
}
BENCHMARK_CAPTURE(NeuralSample, Unified, NeuralTopology::kUnified);
BENCHMARK_CAPTURE(NeuralSample, Decomposed, NeuralTopology::kDecomposed);

void VibrationTickNeural(benchmark::State& state, NeuralTopology t) {
  auto m = BenchMaterial(64, 20);
  m.neural = BenchNeural(t);
  VibrationTicks(state, m);
}
BENCHMARK_CAPTURE(VibrationTickNeural, Unified, NeuralTopology::kUnified);
BENCHMARK_CAPTURE(VibrationTickNeural, Decomposed, NeuralTopology::kDecomposed);

}  // namespace

BENCHMARK_MAIN();
