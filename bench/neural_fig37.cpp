// The Fig. 3.7 comparison on the synthetic AR grids (docs/modeling-neural.md) for other data
// seeds and variants than its test asserts (NeuralFig37.LinearAndNonlinearArGrids): an
// exploration program, not a test. Prints one table line per grid and seed (LPC, Γ_U, Γ_D
// training and held-out mean E_s), Γ_U's validation decision, and for the nonlinear grid the
// paired comparison of Γ_U against LPC held out.
//
//   neural_fig37 [--seeds 40,41,42,43] [--grid linear|nonlinear|both] [--no-decomposed]
//                [--per-cell] [--no-refit] [--rows]
//
// --seeds replaces the data seeds of both grids (default: linear 40, 41; nonlinear 40-43);
// --no-decomposed skips Γ_D (otherwise run on each grid's first seed); --per-cell fits Γ_U's
// linear part per cell everywhere (its stability fallback forced); --no-refit returns the
// linear part fitted on the training rows when it is kept alone; --rows prints E_s per condition
// and E_s^2 split by the bands' frequency ranges.

#include "neural_fig37.hpp"

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

using hapticlab::modeling::Fig37Options;
using hapticlab::modeling::RunArGrid;

int Usage(const char* why) {
  std::fprintf(stderr,
               "neural_fig37: %s\nusage: neural_fig37 [--seeds 40,41] [--grid "
               "linear|nonlinear|both] [--no-decomposed] [--per-cell] [--no-refit] [--rows]\n",
               why);
  return 2;
}

bool ParseSeeds(const std::string& text, std::vector<std::uint64_t>* seeds) {
  for (std::size_t at = 0; at < text.size();) {
    const auto comma = text.find(',', at);
    const std::string cell = text.substr(at, comma == std::string::npos ? comma : comma - at);
    char* end = nullptr;
    const unsigned long long v = std::strtoull(cell.c_str(), &end, 10);
    if (cell.empty() || end != cell.c_str() + cell.size()) return false;
    seeds->push_back(v);
    at = comma == std::string::npos ? text.size() : comma + 1;
  }
  return !seeds->empty();
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::uint64_t> seeds;
  std::string grid = "both";
  bool run_d = true;
  Fig37Options fo;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seeds" && i + 1 < argc) {
      if (!ParseSeeds(argv[++i], &seeds)) return Usage("--seeds: expected integers, e.g. 40,41");
    } else if (a == "--grid" && i + 1 < argc) {
      grid = argv[++i];
      if (grid != "linear" && grid != "nonlinear" && grid != "both")
        return Usage("--grid: expected linear, nonlinear or both");
    } else if (a == "--no-decomposed") {
      run_d = false;
    } else if (a == "--per-cell") {
      fo.per_cell = true;
    } else if (a == "--no-refit") {
      fo.refit = false;
    } else if (a == "--rows") {
      fo.rows = true;
    } else {
      return Usage(("unknown argument " + a).c_str());
    }
  }
  std::printf("AR grid, seed | LPC train  cv | Γ_U train  cv | Γ_D train  cv   (mean E_s)%s\n",
              fo.per_cell ? "  [Γ_U: per-cell AR linear part]" : "");
  if (grid != "nonlinear") {
    const auto s = seeds.empty() ? std::vector<std::uint64_t>{40, 41} : seeds;
    for (const auto seed : s) RunArGrid(false, seed, run_d && seed == s.front(), fo);
  }
  if (grid == "linear") return 0;
  const auto s = seeds.empty() ? std::vector<std::uint64_t>{40, 41, 42, 43} : seeds;
  double sum = 0;
  std::size_t below = 0;
  std::string diffs;
  for (const auto seed : s) {
    const auto cv = RunArGrid(true, seed, run_d && seed == s.front(), fo);
    const double diff = cv.u.mean_es_test - cv.lpc.mean_es_test;
    sum += diff;
    below += diff < 0;
    diffs += fmt::format("{}{}: {:+.3f}", diffs.empty() ? "" : ", ", seed, diff);
  }
  std::printf(
      "nonlinear grid, Γ_U cv - LPC cv by data seed: %s; mean %+.3f; Γ_U below LPC on %zu "
      "of %zu\n",
      diffs.c_str(), sum / static_cast<double>(s.size()), below, s.size());
  return 0;
}
