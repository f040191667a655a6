// Analysis cost of a dissertation-sized design: 20 participants x 3 methods x 10 materials
// with 3 repetitions (1800 ratings): rmANOVA (method x material, with sphericity) plus the
// Tukey comparisons of method, as one `hapticlab analyze` criterion needs.
//
//   build/bench/stats_bench

#include <benchmark/benchmark.h>

#include <random>

#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/tukey.hpp"

namespace {

using namespace hapticlab::stats;

LongTable Design() {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> g(0, 8);
  LongTable t;
  t.key_names = {"subject", "method", "material"};
  t.keys.assign(3, {});
  for (int s = 0; s < 20; ++s)
    for (int m = 0; m < 3; ++m)
      for (int k = 0; k < 10; ++k)
        for (int r = 0; r < 3; ++r) {
          t.keys[0].push_back("P" + std::to_string(s));
          t.keys[1].push_back("M" + std::to_string(m));
          t.keys[2].push_back("K" + std::to_string(k));
          t.y.push_back(55 + 4 * m + k + g(rng));
        }
  return t;
}

void RmAnovaPlusTukey(benchmark::State& state) {
  const auto t = Design();
  for (auto _ : state) {
    const auto a = RmAnova(t, "subject", {"method", "material"});
    const auto tk = TukeyWithin(a, "method", false);
    benchmark::DoNotOptimize(tk.pairs.data());
  }
}
BENCHMARK(RmAnovaPlusTukey)->Unit(benchmark::kMillisecond);

void RmAnovaOnly(benchmark::State& state) {
  const auto t = Design();
  for (auto _ : state)
    benchmark::DoNotOptimize(RmAnova(t, "subject", {"method", "material"}).effects.data());
}
BENCHMARK(RmAnovaOnly)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
