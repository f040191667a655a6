// Vibration modeling throughput (both cores): fitting the AR banks of 100 materials x 25 conditions
// x 10 s recorded at 10 kHz (resample to 2 kHz, band-limit, Levinson-Durbin with the bank's order
// chosen by AIC up to 30). One material's 25 recordings are synthesized once and fitted 100
// times (the fit, not the synthesis, is measured).
//
//   build/bench/modeling_bench

#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/modeling/photometric.hpp"
#include "hapticlab/modeling/vibration.hpp"
#include "hapticlab/renderer/vibration.hpp"

namespace {

using namespace hapticlab;

std::vector<modeling::Recording> Recordings() {
  std::vector<modeling::Recording> recs;
  const double fs = 10000;
  int k = 0;
  for (double v : {0.04, 0.06, 0.08, 0.10, 0.12})
    for (double f : {0.54, 0.89, 1.18, 1.40, 1.91}) {
      renderer::ArFilter fl;
      const double w = 2 * std::numbers::pi * (150 + 1000 * v) / fs, r = 0.98 - 0.01 * f;
      fl.order = 2;
      fl.c[0] = 2 * r * std::cos(w);
      fl.c[1] = -r * r;
      fl.sigma = std::sqrt(v * f);
      fl.active = true;
      renderer::ArSynth s(static_cast<std::uint64_t>(++k));
      modeling::Recording rec{"mem", v, f, fs, std::vector<double>(100000)};
      for (auto& a : rec.acc) a = s.Step(fl);
      recs.push_back(std::move(rec));
    }
  return recs;
}

void Fit(benchmark::State& state, modeling::ResampleQuality q) {
  const auto recs = Recordings();
  modeling::VibrationFitOptions o;
  o.resample = q;
  for (auto _ : state) {
    for (int m = 0; m < 100; ++m)
      benchmark::DoNotOptimize(modeling::FitVibrationBank(recs, o).cells.data());
  }
  state.counters["conditions_per_s"] = benchmark::Counter(
      2500.0 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
// The default (medium-quality resampling, 90 % bandwidth) and the fastest converter (80 %).
void FitHundredMaterialsMedium(benchmark::State& s) { Fit(s, modeling::ResampleQuality::kMedium); }
void FitHundredMaterialsFastest(benchmark::State& s) {
  Fit(s, modeling::ResampleQuality::kFastest);
}
BENCHMARK(FitHundredMaterialsMedium)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
BENCHMARK(FitHundredMaterialsFastest)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

// Photometric stereo: 30 images of 1024 x 1024 (the dome) -> normals and height map.
void Photometric30x1024(benchmark::State& state) {
  const int n = 1024;
  const auto lights = modeling::DomePreset();
  modeling::ImageStack st;
  st.width = st.height = n;
  for (const auto& l : lights) {
    std::vector<float> img(static_cast<std::size_t>(n) * n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const Eigen::Vector3d nn =
            Eigen::Vector3d(-0.2 * std::cos(0.05 * j), 0.1 * std::sin(0.03 * i), 1).normalized();
        img[static_cast<std::size_t>(i) * n + static_cast<std::size_t>(j)] =
            static_cast<float>(0.8 * std::max(0.0, l.direction.dot(nn)));
      }
    st.images.push_back(std::move(img));
  }
  for (auto _ : state)
    benchmark::DoNotOptimize(modeling::PhotometricStereo(st, lights, {}).height_m.data());
}
BENCHMARK(Photometric30x1024)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

// Real-capture conditions: 12 lights, 512 x 512, a sphere with Blinn-Phong highlights masked
// to its disk (the residual rejection and the sparse Poisson solve on the mask).
void PhotometricSpecularMasked12x512(benchmark::State& state) {
  const int n = 512;
  const double R = 230, c = (n - 1) / 2.0;
  std::vector<modeling::Light> lights;
  for (double e : {45.0, 60.0, 75.0})
    for (int a = 0; a < 4; ++a) {
      const double el = e * std::numbers::pi / 180,
                   az = (90.0 * a + (e == 60.0 ? 45 : 0)) * std::numbers::pi / 180;
      lights.push_back(
          {"",
           Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)),
           0});
    }
  modeling::ImageStack st;
  st.width = st.height = n;
  modeling::PhotometricOptions o{.integration = modeling::Integration::kPoisson};
  o.mask.assign(static_cast<std::size_t>(n) * n, 0);
  for (const auto& l : lights) {
    const Eigen::Vector3d h = (l.direction + Eigen::Vector3d::UnitZ()).normalized();
    std::vector<float> img(static_cast<std::size_t>(n) * n, 0.f);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const double x = j - c, y = i - c, r2 = x * x + y * y;
        if (r2 >= R * R) continue;
        const std::size_t k = static_cast<std::size_t>(i) * n + static_cast<std::size_t>(j);
        o.mask[k] = r2 < 0.81 * R * R ? 1 : 0;
        const Eigen::Vector3d nn = Eigen::Vector3d(x, y, std::sqrt(R * R - r2)).normalized();
        const double d = l.direction.dot(nn);
        img[k] = static_cast<float>(
            std::min(1.0, d > 0 ? 0.6 * d + 0.5 * std::pow(std::max(0.0, nn.dot(h)), 40) : 0.0));
      }
    st.images.push_back(std::move(img));
  }
  for (auto _ : state)
    benchmark::DoNotOptimize(modeling::PhotometricStereo(st, lights, o).height_m.data());
}
BENCHMARK(PhotometricSpecularMasked12x512)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
