// Analysis cost of a dissertation-sized design: 20 participants x 3 methods x 10 materials
// with 3 repetitions (1800 ratings): rmANOVA (method x material, with sphericity) plus the
// Tukey comparisons of method, as one `hapticlab analyze` criterion needs. And the linear
// mixed model's cost against the number of rows, with Satterthwaite and with Kenward-Roger df
// (40 participants with a random method slope, crossed with M materials: rows grow by
// repetitions at M = 50, q = 130 random effects; then q grows with M at 20000 rows).
//
//   build/bench/stats_bench [--benchmark_filter=Lmm]

#include <benchmark/benchmark.h>

#include <random>

#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/lmm.hpp"
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

LongTable Crossed(int rows, int materials) {
  std::mt19937_64 rng(2);
  std::normal_distribution<double> g(0, 1);
  LongTable t;
  t.y_name = "score";
  t.key_names = {"participant", "material", "method"};
  t.keys.assign(3, {});
  std::vector<double> p0(40), p1(40), m0(static_cast<std::size_t>(materials));
  for (auto* v : {&p0, &p1, &m0})
    for (double& x : *v) x = g(rng);
  for (int i = 0; i < rows; ++i) {
    const int p = i % 40, k = (i / 40) % materials, m = (i / (40 * materials) + i) % 2;
    t.keys[0].push_back("P" + std::to_string(p));
    t.keys[1].push_back("K" + std::to_string(k));
    t.keys[2].push_back(m ? "haptic" : "audio");
    const auto up = static_cast<std::size_t>(p), uk = static_cast<std::size_t>(k);
    t.y.push_back(50 + 5 * p0[up] + (m ? 3 + 2 * p1[up] : 0) + 3 * m0[uk] + 4 * g(rng));
  }
  return t;
}

void Lmm(benchmark::State& state, bool kenward_roger) {
  const auto t = Crossed(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  LmmOptions o;
  o.kenward_roger = kenward_roger;
  for (auto _ : state)
    benchmark::DoNotOptimize(
        FitLmm(t, "score ~ method + (method | participant) + (1 | material)", o).fixed.data());
}
void LmmSatterthwaite(benchmark::State& state) { Lmm(state, false); }
void LmmKenwardRoger(benchmark::State& state) { Lmm(state, true); }
BENCHMARK(LmmSatterthwaite)
    ->Args({2000, 50})
    ->Args({6000, 50})
    ->Args({20000, 50})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(LmmKenwardRoger)
    ->Args({2000, 50})
    ->Args({6000, 50})
    ->Args({20000, 50})
    ->Args({20000, 500})
    ->Args({20000, 1500})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
