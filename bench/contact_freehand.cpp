// The measurement aid behind the friction-bias numbers of docs/modeling-geometry-contact.md
// (round 4): free-hand recordings with a known truth (tests/modeling/contact_freehand.hpp) fitted
// by the workbench's friction channel with chosen replay options. An experiment program, not a
// test: it prints mu_b's, kappa's and mu_k's error per seed, their mean, mu_b's RMS error and
// its RMS z (error / reported SD). With --coverage 1 it runs instead the coverage experiment of
// ContactFreeHand.NinetyFivePercentIntervalsCoverTheTruth (the whole FitContact over 20 seeds
// from --seed0, noise 4-12 mN) with these replay options.
//
//   contact_freehand [--NAME VALUE]...   (contact_freehand --help lists the names)

#include "contact_freehand.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <string>

#include "hapticlab/modeling/workbench.hpp"

namespace {

using namespace hapticlab;            // NOLINT(google-build-using-namespace): a program
using namespace hapticlab::modeling;  // NOLINT(google-build-using-namespace)

struct Option {
  double value;
  const char* help;
};

std::map<std::string, Option> Options() {
  return {
      {"noise", {0.008, "force noise [N]"}},
      {"pnoise", {1e-7, "position noise [m]"}},
      {"vnoise", {1e-4, "velocity noise [m/s]"}},
      {"rate", {500, "ReplayOptions::max_force_rate_hz"}},
      {"smooth", {0.02, "ReplayOptions::load_smoothing_s"}},
      {"savgol", {1, "ReplayOptions::load_savgol (0 or 1)"}},
      {"psmooth", {0.02, "ReplayOptions::position_smoothing_s"}},
      {"adaptive", {1, "ReplayOptions::position_adaptive (0 or 1)"}},
      {"resolution", {0, "ReplayOptions::position_resolution_m (0: estimated)"}},
      {"seeds", {6, "number of seeds"}},
      {"seed0", {200, "first seed (the tests use 100-119: choices are measured on others)"}},
      {"true-load", {0, "1: replay the noise-free load (an oracle)"}},
      {"load-law", {0, "1: ContactFitOptions::load_from_normal_law (coverage only)"}},
      {"bootstrap", {1, "0: no bootstrap correction (coverage only)"}},
      {"boot-b", {20, "bootstrap replicates (coverage only)"}},
      {"coverage", {0, "1: run the coverage experiment instead"}},
  };
}

// The friction fit on `seeds` recordings, errors against the truth.
void BiasExperiment(const std::map<std::string, Option>& opt, const wb::ReplayOptions& ro) {
  auto at = [&](const char* k) { return opt.at(k).value; };
  const Truth t;
  const int seeds = static_cast<int>(at("seeds"));
  const auto seed0 = static_cast<std::uint64_t>(at("seed0"));
  double sum = 0, sumk = 0, summk = 0, sumsq = 0, sumz = 0;
  for (int s = 0; s < seeds; ++s) {
    const auto seed = seed0 + static_cast<std::uint64_t>(s);
    auto r = wb::PrepareReplay(FreeHand(t, seed, 30, at("noise"), true), ro);
    if (at("true-load") > 0) {  // the load without force noise (oracle)
      const auto r0 = wb::PrepareReplay(FreeHand(t, seed, 30, 0.0, true), ro);
      for (std::size_t i = 0; i < r.samples().size(); ++i)
        r.mutable_samples()[i].fload_N = r0.samples()[i].fload_N;
    }
    wb::Model model;
    wb::AddEffects(&model, ContactEffects(), r);
    wb::FitOptions fo;
    fo.normal = fo.vibration = false;
    fo.uncertainty = true;
    const auto fr = wb::Fit(&model, r, fo);
    double mb = 0, kp = 0, mk = 0, sdb = 0;
    for (const auto& p : fr.Find(wb::Channel::kFriction)->params) {
      if (p.name == "mu_b") mb = p.value, sdb = p.sd;
      if (p.name == "kappa") kp = p.value;
      if (p.name == "mu_k") mk = p.value;
    }
    fmt::print("seed {} mu_b {:+.3f}% (sd {:.3f}%) kappa {:+.3f}% mu_k {:+.4f}% res {}\n", seed,
               100 * (mb / t.mu_b_Ns_per_m - 1), 100 * sdb / t.mu_b_Ns_per_m,
               100 * (kp / t.kappa_N_per_m - 1), 100 * (mk / t.mu_k - 1), r.position_resolution_m);
    sumsq += std::pow(mb / t.mu_b_Ns_per_m - 1, 2);
    sumz += std::pow((mb - t.mu_b_Ns_per_m) / sdb, 2);
    sum += mb / t.mu_b_Ns_per_m - 1, sumk += kp / t.kappa_N_per_m - 1, summk += mk / t.mu_k - 1;
  }
  fmt::print("RMS mu_b error {:.3f}%, RMS z {:.2f}\n", 100 * std::sqrt(sumsq / seeds),
             std::sqrt(sumz / seeds));
  fmt::print("MEAN mu_b {:+.3f}% kappa {:+.3f}% mu_k {:+.4f}%\n", 100 * sum / seeds,
             100 * sumk / seeds, 100 * summk / seeds);
}

}  // namespace

int main(int argc, char** argv) {
  auto opt = Options();
  for (int i = 1; i < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      fmt::print("contact_freehand [--NAME VALUE]...\n");
      for (const auto& [k, o] : opt)
        fmt::print("  --{:11s} {} (default {:g})\n", k, o.help, o.value);
      return 0;
    }
    const auto it = a.rfind("--", 0) == 0 ? opt.find(a.substr(2)) : opt.end();
    char* end = nullptr;
    const double v = i + 1 < argc ? std::strtod(argv[i + 1], &end) : 0;
    if (it == opt.end() || i + 1 >= argc || end == argv[i + 1] || *end != 0 || !std::isfinite(v)) {
      fmt::print(stderr, "contact_freehand: expected --NAME NUMBER at '{}' (--help lists them)\n",
                 a);
      return 2;
    }
    it->second.value = v;
  }
  auto at = [&](const char* k) { return opt.at(k).value; };
  g_pnoise = at("pnoise");
  g_vnoise = at("vnoise");
  wb::ReplayOptions ro;
  ro.max_force_rate_hz = at("rate");
  ro.load_smoothing_s = at("smooth");
  ro.load_savgol = at("savgol") > 0;
  ro.position_smoothing_s = at("psmooth");
  ro.position_adaptive = at("adaptive") > 0;
  ro.position_resolution_m = at("resolution");
  if (at("coverage") > 0) {
    ContactFitOptions o;
    o.replay = ro;
    o.load_from_normal_law = at("load-law") > 0;
    o.bootstrap = at("bootstrap") > 0;
    o.bootstrap_options.replicates = static_cast<int>(at("boot-b"));
    RunCoverage(o, static_cast<std::uint64_t>(at("seed0")));
    return 0;
  }
  BiasExperiment(opt, ro);
  return 0;
}
