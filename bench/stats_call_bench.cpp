// Cost of one full statistics call as a process, the way analysts and scripts run it:
// rmANOVA (method x material, sphericity) + Tukey on method for one criterion of
// tests/data/stats/example_raw.csv (10 subjects x 3 x 10, 3 repetitions), through
//   1. hapticlab-stats rm-anova + hapticlab-stats tukey (the lean binary),
//   2. hapticlab stats rm-anova + tukey (the full CLI, which loads every library),
//   3. Rscript bench/stats_call.R (afex + emmeans, one process doing both),
// each run N times; prints medians and the ratio R / hapticlab-stats. Rscript is skipped,
// with a note, where it is not installed. Not a test: nothing here asserts a time.
//
//   build/bench/stats_call_bench [N]      (default N = 20; R runs min(N, 5) times)

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

double MedianSeconds(const std::string& command, int n) {
  std::vector<double> t;
  for (int i = 0; i < n; ++i) {
    const auto a = std::chrono::steady_clock::now();
    const int rc = std::system(("(" + command + ") > /dev/null 2>&1").c_str());
    const auto b = std::chrono::steady_clock::now();
    if (rc != 0) {
      fmt::print(stderr, "failed ({}): {}\n", rc, command);
      std::exit(1);
    }
    t.push_back(std::chrono::duration<double>(b - a).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::max(1, std::atoi(argv[1])) : 20;
  const std::string src = HL_SOURCE_DIR, csv = src + "/tests/data/stats/example_raw.csv";
  const std::string args =
      " --csv " + csv +
      " --dv score --subject subject --within method,material --where criterion=realism";
  const std::string lean = HL_STATS_CLI_PATH, full = std::string(HL_CLI_PATH) + " stats";
  const std::string lean_call =
      lean + " rm-anova" + args + " && " + lean + " tukey" + args + " --factor method";
  const std::string full_call =
      full + " rm-anova" + args + " && " + full + " tukey" + args + " --factor method";
  fmt::print("one call = rmANOVA (method x material) + Tukey on method, {} runs each, medians:\n",
             n);
  const double t_lean = MedianSeconds(lean_call, n);
  fmt::print("  hapticlab-stats (lean binary)      {:8.4f} s\n", t_lean);
  const double t_help = MedianSeconds(lean + " --help", n);
  fmt::print("    of which start-up (--help)       {:8.4f} s\n", t_help);
  const double t_full = MedianSeconds(full_call, n);
  fmt::print("  hapticlab stats (full CLI)         {:8.4f} s\n", t_full);
  if (std::system("command -v Rscript > /dev/null 2>&1") != 0 ||
      std::system("Rscript -e 'library(afex); library(emmeans)' > /dev/null 2>&1") != 0) {
    fmt::print("  Rscript with afex + emmeans: not installed, R comparison skipped\n");
    return 0;
  }
  const double t_r = MedianSeconds("Rscript " + src + "/bench/stats_call.R " + csv, std::min(n, 5));
  fmt::print("  Rscript afex + emmeans             {:8.4f} s\n", t_r);
  fmt::print("R / hapticlab-stats = {:.0f}x; R / hapticlab stats = {:.0f}x\n", t_r / t_lean,
             t_r / t_full);
  return 0;
}
