// hapticlab model fit-contact: contact and friction parameters from measurements.

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "cli_common.hpp"
#include "cmd_model.hpp"
#include "commands.hpp"
#include "fit_summary_json.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/measurement.hpp"
#include "hapticlab/modeling/contact.hpp"
#include "hapticlab/modeling/neural.hpp"
#include "hapticlab/modeling/photometric.hpp"
#include "hapticlab/modeling/vibration.hpp"
#include "hapticlab/renderer/energy.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/renderer/penn_import.hpp"
#include "hapticlab/runner/offline.hpp"
#include "hapticlab/stats/plot.hpp"

namespace hapticlab::cli {
namespace {

struct FitContactArgs {
  std::string measurement, pokes, out;
  bool json = false;
};

// The fitted model as a renderer material (effects, [contact], [friction]) under a comment
// block of the estimates' intervals; reloaded to check that it loads.
void WriteContactModel(const FitContactArgs& o, const modeling::ContactFit& f) {
  // Written through the model types: the renderer's material, effects included.
  renderer::MaterialModel mm;
  mm.name = std::filesystem::path(o.out).stem().string();
  mm.effects = modeling::ContactEffects();
  mm.contact.texture = {f.K.value, f.B.value, f.n.value};
  mm.contact.base = {0, 0, 1};
  mm.contact.layer_thickness_m = 0.005;  // no base felt: thicker than any measured penetration
  mm.friction = {f.kappa_N_per_m.value, f.mu_k.value, f.mu_b_Ns_per_m.value};
  auto ci = [](const char* k, const modeling::Estimate& e) {
    return fmt::format("#   {:14s} {:.6g} +- {:.3g} (95 %: {:.6g} .. {:.6g})\n", k, e.value, e.sd,
                       e.lo95, e.hi95);
  };
  std::string text = fmt::format(
      "# Fitted by hapticlab model fit-contact from {} (SI units).\n# Uncertainty: {}.\n",
      o.measurement, f.uncertainty_method);
  text += ci("texture_K", f.K) + ci("texture_B", f.B) + ci("texture_n", f.n) +
          ci("kappa_N_per_m", f.kappa_N_per_m) + ci("mu_k", f.mu_k) +
          ci("mu_b_Ns_per_m", f.mu_b_Ns_per_m);
  text += renderer::MaterialToToml(mm);
  WriteTextFile(o.out, text);
  renderer::LoadMaterial(o.out);  // what was written is a loadable material
}

nlohmann::json FitContactJson(const modeling::ContactFit& f, const std::string& out) {
  auto est = [](const modeling::Estimate& e) {
    return nlohmann::json{{"value", e.value}, {"sd", e.sd}, {"lo95", e.lo95}, {"hi95", e.hi95}};
  };
  return nlohmann::json{
      {"hunt_crossley",
       {{"K", f.K.value},
        {"B", f.B.value},
        {"n", f.n.value},
        {"K1mm_N", f.K1mm_N.value},
        {"B1mm", f.B1mm_Ns_per_m.value}}},
      {"dahl",
       {{"kappa", f.kappa_N_per_m.value}, {"mu_k", f.mu_k.value}, {"mu_b", f.mu_b_Ns_per_m.value}}},
      {"uncertainty",
       {{"K", est(f.K)},
        {"B", est(f.B)},
        {"n", est(f.n)},
        {"K1mm_N", est(f.K1mm_N)},
        {"B1mm", est(f.B1mm_Ns_per_m)},
        {"kappa", est(f.kappa_N_per_m)},
        {"mu_k", est(f.mu_k)},
        {"mu_b", est(f.mu_b_Ns_per_m)}}},
      {"uncertainty_method", f.uncertainty_method},
      {"friction_bootstrap", BootstrapJson(f.bootstrap)},
      {"residual_rms_N", {{"hunt_crossley", f.normal_rms_N}, {"dahl", f.friction_rms_N}}},
      {"samples", {{"strokes", f.stroke_samples}, {"pokes", f.poke_samples}}},
      {"poke_source", f.poke_source},
      {"algorithm1",
       {{"passes", f.algorithm1.passes},
        {"converged", f.algorithm1.converged},
        {"kappa", f.algorithm1.kappa_N_per_m},
        {"mu_k", f.algorithm1.mu_k},
        {"mu_b", f.algorithm1.mu_b_Ns_per_m}}},
      {"fit",
       {{"friction", FitSummaryJson(f.friction_summary)},
        {"normal_force", FitSummaryJson(f.normal_summary)}}},
      {"usable", f.IsUsable()},
      {"out", out}};
}

void PrintFitContact(const modeling::ContactFit& f, const std::string& out) {
  auto pm = [](const modeling::Estimate& e) {
    return fmt::format("{:.5g} +- {:.2g} [{:.5g}, {:.5g}]", e.value, e.sd, e.lo95, e.hi95);
  };
  fmt::print(
      "Hunt-Crossley ({} samples <= 2 N from {}): K = {} N/m^n, B = {} N s/m^(n+1), n = {}; "
      "rms {:.4f} N\n",
      f.poke_samples, f.poke_source, pm(f.K), pm(f.B), pm(f.n), f.normal_rms_N);
  fmt::print(
      "Dahl ({} samples; Algorithm 1: {} passes{}, kappa {:.4g}, mu_k {:.4f}, mu_b {:.4f}): "
      "kappa = {} N/m, "
      "mu_k = {}, mu_b = {} N s/m; rms {:.4f} N\n",
      f.stroke_samples, f.algorithm1.passes, f.algorithm1.converged ? "" : ", not converged",
      f.algorithm1.kappa_N_per_m, f.algorithm1.mu_k, f.algorithm1.mu_b_Ns_per_m,
      pm(f.kappa_N_per_m), pm(f.mu_k), pm(f.mu_b_Ns_per_m), f.friction_rms_N);
  fmt::print("{}\n{}\n", FitSummaryLine(f.friction_summary), FitSummaryLine(f.normal_summary));
  fmt::print("{}\nuncertainty: {}\nwrote {}\n", BootstrapLine(f.bootstrap), f.uncertainty_method,
             out);
}

int RunFitContact(const FitContactArgs& o) {
  const auto m = ReadMeasurementCsv(o.measurement);
  Measurement pokes;
  if (!o.pokes.empty()) pokes = ReadMeasurementCsv(o.pokes);
  const auto f = modeling::FitContact(m, o.pokes.empty() ? nullptr : &pokes);
  WriteContactModel(o, f);
  if (o.json)
    PrintJson(FitContactJson(f, o.out));
  else
    PrintFitContact(f, o.out);
  if (!f.IsUsable()) {
    fmt::print(
        stderr,
        "fit-contact: a fit is not usable (see the fit lines); {} was written for inspection\n",
        o.out);
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

void AddFitContact(CLI::App& model) {
  auto o = std::make_shared<FitContactArgs>();
  auto* cmd = model.add_subcommand(
      "fit-contact",
      "Identify friction and stiffness on a flat sample with its surface at z = 0 (dissertation\n"
      "ch. IV.3) with the workbench's engine: vector Dahl friction with Coulomb and viscous terms\n"
      "replayed over the measured 2-D path (strokes in any direction), started by Algorithm 1 and\n"
      "refined jointly by Ceres; Hunt-Crossley K, B, n on pokes (samples above 2 N discarded).\n"
      "Pokes are the samples without sliding in --measurement, or a separate --pokes file.\n"
      "Uncertainties: cluster jackknife over 3 s clusters of blocks, 95 % intervals; kappa, mu_k\n"
      "and mu_b are bias-corrected and their standard errors at least the jackknife's, by a\n"
      "parametric bootstrap through the preprocessing (20 simulated copies of the measurement "
      "with\n"
      "its own noise; docs/modeling-geometry-contact.md). Prints each\n"
      "solve's termination, iterations, cost and parameters at bounds; exits 1 when a fit is not\n"
      "usable. Writes a material model (effects, [contact], [friction]) for `model build`.");
  cmd->add_option("--measurement", o->measurement, "Strokes (and pokes): measurement CSV v1")
      ->required();
  cmd->add_option("--pokes", o->pokes, "Pokes in a separate measurement CSV v1");
  cmd->add_option("-o,--out", o->out,
                  "Material model TOML to write ([contact], [friction], effects)")
      ->required();
  cmd->add_flag("--json", o->json,
                "Print "
                "{\"hunt_crossley\":{K,B,n},\"dahl\":{kappa,mu_k,mu_b},\"uncertainty\":{...},"
                "\"friction_bootstrap\":{...},"
                "\"fit\":{friction,"
                "normal_force},\"usable\"}");
  cmd->callback([o] { RunGuarded([&] { return RunFitContact(*o); }); });
}

}  // namespace hapticlab::cli
