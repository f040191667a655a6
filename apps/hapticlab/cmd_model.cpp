// hapticlab model: check, render, energy and import material models.

#include <fmt/core.h>

#include <algorithm>
#include <cstdio>
#include <regex>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "fit_summary_json.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/measurement.hpp"
#include <unistd.h>
#include "hapticlab/renderer/energy.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/renderer/penn_import.hpp"
#include "hapticlab/modeling/contact.hpp"
#include "hapticlab/modeling/photometric.hpp"
#include <opencv2/imgcodecs.hpp>
#include <opencv2/core.hpp>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include "hapticlab/modeling/vibration.hpp"
#include "hapticlab/modeling/neural.hpp"
#include <mutex>
#include "hapticlab/stats/plot.hpp"
#include <filesystem>
#include "hapticlab/runner/offline.hpp"

namespace hapticlab::cli {
namespace {

using renderer::ForceAlgorithm;

void AddCheck(CLI::App& model) {
  auto path = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  auto* cmd = model.add_subcommand("check", "Load and validate a material model; print a summary");
  cmd->alias("show");
  cmd->add_option("MODEL", *path, "Material model (.toml)")->required();
  cmd->add_flag("--json", *json, "Print the summary as JSON");
  cmd->callback([path, json] {
    RunGuarded([&] {
      const auto m = renderer::LoadMaterial(*path);
      nlohmann::json j = {{"name", m.name},
                          {"effects", m.effects},
                          {"texture", {{"K", m.contact.texture.K}, {"B", m.contact.texture.B}, {"n", m.contact.texture.n}}},
                          {"friction", {{"kappa_N_per_m", m.friction.kappa_N_per_m}, {"mu_k", m.friction.mu_k},
                                        {"mu_b_Ns_per_m", m.friction.mu_b_Ns_per_m}}},
                          {"height_map", {{"width", m.geometry->width()}, {"height", m.geometry->height()},
                                          {"pitch_m", m.geometry->pitch_m()},
                                          {"range_m", m.geometry->max_m() - m.geometry->min_m()}}},
                          {"vibration", {{"cells", m.vibration.cells.size()}, {"order", m.vibration.order()},
                                         {"sample_rate_hz", m.vibration.sample_rate_hz}}},
                          {"hybrid_cutoff_hz", m.hybrid_cutoff_hz}};
      if (*json) fmt::print("{}\n", j.dump(2));
      else fmt::print("{}: ok\n{}\n", *path, j.dump(2));
      return kExitOk;
    });
  });
}

void AddRender(CLI::App& model) {
  struct O {
    std::string model, trajectory, out, vib_out, algorithm = "fric2", force_source = "auto";
    double force_rate = 1000, vib_rate = 10000, max_force = 8;
    bool no_vibration = false, no_filter = false;
    std::uint64_t seed = 1;
  };
  auto o = std::make_shared<O>();
  auto* cmd = model.add_subcommand(
      "render",
      "Run the real-time ticks offline over a recorded trajectory (measurement CSV v1;\n"
      "velocities are differentiated when absent). When the trajectory has forces, its normal\n"
      "force (fz_N) drives the vibration model, which plays while fz_N > 0 (--force-source);\n"
      "the rendered force still follows the geometry. Writes one row per trajectory sample:\n"
      "model force, commanded force, normal force, friction, speed, contact, fault, and the\n"
      "vibration sample at that time.");
  cmd->add_option("--model", o->model, "Material model (.toml)")->required();
  cmd->add_option("--trajectory", o->trajectory, "Trajectory (measurement CSV v1)")->required();
  cmd->add_option("--out", o->out, "Output CSV")->required();
  cmd->add_option("--vibration-out", o->vib_out, "Also write every vibration sample (CSV t_s,acc_mps2)");
  cmd->add_option("--algorithm", o->algorithm, "Force algorithm")
      ->check(CLI::IsMember({"wall", "norm", "fric1", "fric2", "none"}))->capture_default_str();
  cmd->add_option("--vibration-rate", o->vib_rate, "Vibration loop rate [Hz]")->capture_default_str();
  cmd->add_option("--max-force", o->max_force, "Device force limit [N]")->capture_default_str();
  cmd->add_option("--force-source", o->force_source,
                  "Normal force of the vibration model: auto (the trajectory's when it has forces),\n"
                  "trajectory (required), model (the rendered normal force)")
      ->check(CLI::IsMember({"auto", "trajectory", "model"}))->capture_default_str();
  cmd->add_flag("--no-vibration", o->no_vibration, "Force only");
  cmd->add_flag("--no-hybrid-filter", o->no_filter, "Do not low/high-pass at the model's f_c");
  cmd->add_option("--seed", o->seed, "Vibration noise seed")->capture_default_str();
  cmd->callback([o] {
    RunGuarded([&] {
      const auto m = renderer::LoadMaterial(o->model);
      const auto traj = ReadMeasurementCsv(o->trajectory, {.kinematics_only = true});
      if (traj.rows.size() < 2) throw InputError(o->trajectory, 0, "", "needs at least two samples");
      renderer::RenderOptions ro;
      ro.algorithm = renderer::ParseForceAlgorithm(o->algorithm);
      ro.vibration = !o->no_vibration;
      ro.hybrid_filter = !o->no_filter;
      ro.vibration_rate_hz = o->vib_rate;
      ro.max_force_N = o->max_force;
      ro.seed = o->seed;
      // The force loop runs at the trajectory's own rate.
      ro.force_rate_hz = static_cast<double>(traj.rows.size() - 1) / (traj.rows.back().t_s - traj.rows.front().t_s);
      ro.stale_after_s = 1e9;  // offline: samples are never stale
      if (o->force_source == "trajectory" && !traj.has_forces)
        throw InputError(o->trajectory, 0, "fz_N", "--force-source trajectory needs force columns (fx_N, fy_N, fz_N)");
      runner::OfflineOptions oo;
      oo.measured_normal_force = o->force_source != "model" && traj.has_forces;
      const auto res = runner::RenderOffline(m, ro, traj, oo);
      FILE* f = std::fopen(o->out.c_str(), "w");
      if (!f) throw std::runtime_error(o->out + ": cannot write");
      std::fprintf(f, "t_s,fx_N,fy_N,fz_N,cmd_fx_N,cmd_fy_N,cmd_fz_N,normal_N,friction_N,speed_mps,in_contact,fault,acc_mps2\n");
      for (const auto& r : res.rows)
        std::fprintf(f, "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d,%d,%.9g\n", r.t_s, r.force_N.x(),
                     r.force_N.y(), r.force_N.z(), r.command_N.x(), r.command_N.y(), r.command_N.z(),
                     r.normal_N, r.friction_N, r.speed_mps, r.in_contact ? 1 : 0, r.fault ? 1 : 0, r.acc_mps2);
      if (std::fclose(f) != 0) throw std::runtime_error(o->out + ": write failed");
      if (!o->vib_out.empty()) {
        FILE* v = std::fopen(o->vib_out.c_str(), "w");
        if (!v) throw std::runtime_error(o->vib_out + ": cannot write");
        std::fprintf(v, "t_s,acc_mps2\n");
        for (std::size_t k = 0; k < res.vibration_mps2.size(); ++k)
          std::fprintf(v, "%.9g,%.9g\n", traj.rows.front().t_s + static_cast<double>(k) / ro.vibration_rate_hz, res.vibration_mps2[k]);
        if (std::fclose(v) != 0) throw std::runtime_error(o->vib_out + ": write failed");
      }
      fmt::print(stderr, "rendered {} force ticks at {:.0f} Hz and {} vibration samples (vibration force: {}) -> {}\n",
                 res.rows.size(), ro.force_rate_hz, res.vibration_mps2.size(),
                 oo.measured_normal_force ? "the trajectory's fz_N" : "the rendered normal force", o->out);
      return kExitOk;
    });
  });
}

void AddEnergy(CLI::App& model) {
  struct O {
    std::string algorithm = "norm", sine, model;
    double dx = 1e-4, dz = 0, stiffness = 1000, mu = 0;
    int steps = 20000;
    bool json = false;
  };
  auto o = std::make_shared<O>();
  auto* cmd = model.add_subcommand(
      "energy",
      "Work done by the rendered force field around a closed path on h = A sin(2 pi x / l)\n"
      "(dissertation Fig. 5.3). norm uses path A: (0,0)->(l/4,0)->(l/4,A)->(0,A)->(0,0), z from\n"
      "the mean surface, and is compared with eq. (5.2). fric1/fric2/wall use path B: down\n"
      "dz_max, along dx_max, up, back; the bound of eq. (5.3) is reported. Without --model,\n"
      "a linear texture layer (K = --stiffness, no damping) with friction --mu is used.\n"
      "Positive energy is created by the surface (non-passive).");
  cmd->add_option("--algorithm", o->algorithm, "Force algorithm")
      ->check(CLI::IsMember({"wall", "norm", "fric1", "fric2", "none"}))->capture_default_str();
  cmd->add_option("--sine", o->sine, "AMPLITUDE_M,WAVELENGTH_M of the test texture")->required();
  cmd->add_option("--model", o->model, "Take contact and friction parameters from this model");
  cmd->add_option("--stiffness", o->stiffness, "Texture stiffness K without --model [N/m]")->capture_default_str();
  cmd->add_option("--mu", o->mu, "Coulomb coefficient without --model")->capture_default_str();
  cmd->add_option("--dx-max", o->dx, "Path B tangential excursion [m]")->capture_default_str();
  cmd->add_option("--dz-max", o->dz, "Path B penetration [m] (default: the amplitude)");
  cmd->add_option("--steps", o->steps, "Integration steps per side")->capture_default_str();
  cmd->add_flag("--json", o->json, "Print {\"energy_J\", \"closed_form_J\", ...} as JSON");
  cmd->callback([o] {
    RunGuarded([&] {
      const auto comma = o->sine.find(',');
      double a = 0, l = 0;
      try {
        if (comma == std::string::npos) throw std::invalid_argument("");
        a = std::stod(o->sine.substr(0, comma));
        l = std::stod(o->sine.substr(comma + 1));
      } catch (const std::exception&) {
        throw InputError("", 0, "--sine", "expected AMPLITUDE_M,WAVELENGTH_M, got '" + o->sine + "'");
      }
      if (!(a > 0) || !(l > 0)) throw InputError("", 0, "--sine", "amplitude and wavelength must be > 0");
      renderer::MaterialModel m;
      if (!o->model.empty()) {
        m = renderer::LoadMaterial(o->model);
      } else {
        m.contact.texture = {o->stiffness, 0, 1};
        m.contact.base = {2 * o->stiffness, 0, 1};
        m.contact.layer_thickness_m = 1e-3;
        m.friction = {2000, o->mu, 0};
      }
      const auto alg = renderer::ParseForceAlgorithm(o->algorithm);
      renderer::EnergyPath path;
      path.kind = alg == ForceAlgorithm::kNorm ? renderer::EnergyPath::Kind::kA : renderer::EnergyPath::Kind::kB;
      path.dx_max_m = o->dx;
      path.dz_max_m = o->dz > 0 ? o->dz : a;
      path.steps = o->steps;
      const auto r = renderer::ComputeEnergy(m, alg, a, l, path);
      nlohmann::json j = {{"algorithm", o->algorithm},
                          {"path", path.kind == renderer::EnergyPath::Kind::kA ? "A" : "B"},
                          {"energy_J", r.energy_J},
                          {"normal_energy_J", r.normal_energy_J},
                          {"tangential_energy_J", r.tangential_energy_J},
                          {"closed_form_J", nlohmann::json()}};
      if (path.kind == renderer::EnergyPath::Kind::kA) {
        if (r.has_closed_form) j["closed_form_J"] = r.closed_form_J;
      } else {
        // Path B's closed form covers the normal part only (friction adds to it).
        if (r.has_closed_form) j["normal_closed_form_J"] = r.closed_form_J;
        j["bound_J"] = r.bound_J;
        j["gain_bound_J"] = r.gain_bound_J;
      }
      if (o->json) {
        fmt::print("{}\n", j.dump(2));
      } else {
        fmt::print("algorithm {} on path {}: energy {:.6e} J", o->algorithm, j["path"].get<std::string>(), r.energy_J);
        if (r.has_closed_form && path.kind == renderer::EnergyPath::Kind::kA)
          fmt::print(" (eq. 5.2: {:.6e} J, difference {:.3f} %)", r.closed_form_J,
                     100 * (r.energy_J - r.closed_form_J) / r.closed_form_J);
        fmt::print("\n");
        if (path.kind == renderer::EnergyPath::Kind::kB)
          fmt::print("normal part {:.3e} J (closed form {:.3e} J), tangential part {:.3e} J;\n"
                     "eq. (5.3) scale K mu^2 dx dz = {:.3e} J; gain bound = {:.3e} J\n",
                     r.normal_energy_J, r.closed_form_J, r.tangential_energy_J, r.bound_J, r.gain_bound_J);
      }
      return kExitOk;
    });
  });
}

void AddImportPenn(CLI::App& model) {
  struct O {
    std::string xml, out;
    double cutoff = 0;
  };
  auto o = std::make_shared<O>();
  auto* cmd = model.add_subcommand(
      "import-penn",
      "Convert a Penn Haptic Texture Toolkit model set (Models_<name>.xml, from your own copy;\n"
      "its licence forbids redistribution) into a HapticLab material model. The vibration\n"
      "bank, its modelled range (maxSpeed, maxForce: saturated as the toolkit does) and mu are\n"
      "imported; the bank plays down to the toolkit's 0.05 mm/s; contact and geometry are left\n"
      "at flat defaults to be fitted. With flat geometry the vibration carries the whole\n"
      "texture, so the hybrid cut-off is 0 (no split) unless --cutoff-hz says otherwise.");
  cmd->add_option("--xml", o->xml, "Penn model set XML")->required();
  cmd->add_option("-o,--out", o->out, "Material model to write (.toml)")->required();
  cmd->add_option("--cutoff-hz", o->cutoff, "Hybrid cut-off f_c to store [Hz]; 0: no split")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->callback([o] {
    RunGuarded([&] {
      auto r = renderer::ImportPennXml(o->xml);
      r.model.hybrid_cutoff_hz = o->cutoff;
      r.model.effects = {"coulomb", "vibration-speed", "vibration-force"};
      FILE* f = std::fopen(o->out.c_str(), "w");
      if (!f) throw std::runtime_error(o->out + ": cannot write");
      const std::string text = "# Imported from " + o->xml + " (Penn Haptic Texture Toolkit format).\n" +
                               renderer::MaterialToToml(r.model);
      std::fputs(text.c_str(), f);
      if (std::fclose(f) != 0) throw std::runtime_error(o->out + ": write failed");
      const auto& b = r.model.vibration;
      fmt::print("{}: {} models ({}), order {}, mu {:.4f}; LSF reconstruction error {:.2e}; {} -> {}\n", o->xml,
                 b.cells.size(), r.arma ? "ARMA" : "AR", b.order(), r.model.friction.mu_k,
                 r.max_lsf_reconstruction_error,
                 r.has_range ? fmt::format("range {:g} mm/s x {:g} N", b.max_speed_mps * 1e3, b.max_force_N)
                             : std::string("no maxSpeed/maxForce: no saturation"),
                 o->out);
      return kExitOk;
    });
  });
}

std::vector<double> ParseList(const std::string& s, const char* opt) {
  std::vector<double> out;
  std::size_t a = 0;
  while (a <= s.size()) {
    const auto b = s.find(',', a);
    const std::string part = s.substr(a, b == std::string::npos ? std::string::npos : b - a);
    try {
      if (!part.empty()) out.push_back(std::stod(part));
    } catch (const std::exception&) {
      throw InputError("", 0, opt, "expected comma-separated numbers, got '" + s + "'");
    }
    if (b == std::string::npos) break;
    a = b + 1;
  }
  return out;
}

struct VibArgs {
  std::string recordings, out, order = "auto", criterion = "aic";
  double rate = 2000, band_lo = 20;
};

void AddVibOptions(CLI::App* cmd, VibArgs& a) {
  cmd->add_option("--recordings", a.recordings,
                  "Folder of measurement CSV v1 files with acc_mps2, one per (speed, force) condition")
      ->required();
  cmd->add_option("--rate", a.rate, "Model sample rate [Hz] (2000 in the thesis)")->capture_default_str();
  cmd->add_option("--order", a.order, "AR order: a number, or auto (information criterion)")->capture_default_str();
  cmd->add_option("--criterion", a.criterion, "Order criterion")->check(CLI::IsMember({"aic", "bic"}))->capture_default_str();
  cmd->add_option("--band-low", a.band_lo, "High-pass of the band limit [Hz]")->capture_default_str();
}

modeling::VibrationFitOptions VibOptions(const VibArgs& a) {
  modeling::VibrationFitOptions o;
  o.model_rate_hz = a.rate;
  o.band_lo_hz = a.band_lo;
  o.criterion = a.criterion == "bic" ? modeling::OrderCriterion::kBic : modeling::OrderCriterion::kAic;
  if (a.order != "auto") {
    try {
      o.order = std::stoi(a.order);
    } catch (const std::exception&) {
      throw InputError("", 0, "--order", "expected a number or auto, got '" + a.order + "'");
    }
    if (o.order < 1 || o.order > 64) throw InputError("", 0, "--order", "expected 1..64");
  }
  return o;
}

void AddFitVibration(CLI::App& model) {
  auto a = std::make_shared<VibArgs>();
  auto* cmd = model.add_subcommand(
      "fit-vibration",
      "Fit the AR bank over (speed, force) from contact-acceleration recordings: resample to\n"
      "the model rate, band-limit, Levinson-Durbin per condition with one order for the bank.\n"
      "Writes a TOML file holding a [vibration] table; reference it from a material model\n"
      "with [vibration] file = \"BANK.toml\" (docs/modeling-vibration.md).");
  AddVibOptions(cmd, *a);
  cmd->add_option("-o,--out", a->out, "Bank file to write (.toml)")->required();
  cmd->callback([a] {
    RunGuarded([&] {
      const auto recs = modeling::LoadRecordings(a->recordings);
      const auto bank = modeling::FitVibrationBank(recs, VibOptions(*a));
      renderer::MaterialModel holder;
      holder.vibration = bank;
      std::string text = renderer::MaterialToToml(holder);
      text = text.substr(text.find("[vibration]"));  // the bank alone
      FILE* f = std::fopen(a->out.c_str(), "w");
      if (!f) throw std::runtime_error(a->out + ": cannot write");
      std::fputs(("# AR bank fitted by hapticlab model fit-vibration from " + a->recordings + "\n").c_str(), f);
      std::fputs(text.c_str(), f);
      if (std::fclose(f) != 0) throw std::runtime_error(a->out + ": write failed");
      fmt::print("{} recordings -> {} cells ({}), order {} at {:.0f} Hz -> {}\n", recs.size(), bank.cells.size(),
                 bank.grid_speeds_mps.empty() ? "triangulated" : "grid", bank.order(), bank.sample_rate_hz, a->out);
      return kExitOk;
    });
  });
}

void AddFitNeural(CLI::App& model) {
  struct O {
    VibArgs a;
    std::string topology = "unified";
    int epochs = 40;
    double input_noise = 0.3;
    std::uint64_t seed = 1;
    int threads = 0;
  };
  auto o = std::make_shared<O>();
  auto* cmd = model.add_subcommand(
      "fit-neural",
      "Train the neural texture model (dissertation ch. III.3, Fig. 3.3) from recordings on a full\n"
      "speed x force grid: four bands (20-100, 100-200, 200-500, 500-1000 Hz; decimation 8, 4,\n"
      "1, 1), an MLP per band with 50 inputs (Γ_U: one per band with v and f as inputs, hidden\n"
      "30-25-15-5; Γ_D: one per band and grid cell, 30-25-15-5 for band 1 and 30-15-5 for the\n"
      "others), Adam with mini-batches and early stopping. Writes a neural model file; reference\n"
      "it from a material with [neural] file = \"F\" (docs/modeling-neural.md).");
  cmd->add_option("--recordings", o->a.recordings, "Folder of measurement CSV v1 files with acc_mps2, one per condition")
      ->required();
  cmd->add_option("--topology", o->topology, "unified (Γ_U) or decomposed (Γ_D)")
      ->check(CLI::IsMember({"unified", "decomposed"}))
      ->capture_default_str();
  cmd->add_option("-o,--out", o->a.out, "Neural model file to write (.toml)")->required();
  cmd->add_option("--rate", o->a.rate, "Model sample rate [Hz]")->capture_default_str();
  cmd->add_option("--epochs", o->epochs, "Maximum training epochs per network")->capture_default_str()->check(CLI::Range(1, 10000));
  cmd->add_option("--input-noise", o->input_noise, "Noise on training histories (units of the band RMS)")->capture_default_str();
  cmd->add_option("--seed", o->seed, "Initialisation, shuffling and noise seed")->capture_default_str();
  cmd->add_option("--threads", o->threads, "Networks trained in parallel (0: all cores)")->capture_default_str();
  cmd->callback([o] {
    RunGuarded([&] {
      const auto recs = modeling::LoadRecordings(o->a.recordings);
      modeling::NeuralFitOptions no;
      no.topology = o->topology == "unified" ? renderer::NeuralTopology::kUnified : renderer::NeuralTopology::kDecomposed;
      no.preprocess = VibOptions(o->a);
      no.train.max_epochs = o->epochs;
      no.train.seed = o->seed;
      no.input_noise = o->input_noise;
      no.threads = o->threads;
      std::mutex mu;
      no.progress = [&](const std::string& what, int done, int total) {
        std::lock_guard<std::mutex> lock(mu);
        fmt::print(stderr, "fit-neural: {}/{} networks trained ({})\n", done, total, what);
      };
      const auto m = modeling::FitNeural(recs, no);
      renderer::SaveNeuralModel(m, o->a.out);
      fmt::print("{} recordings ({} speeds x {} forces) -> {} model, {} bands -> {}\n", recs.size(), m.speeds_mps.size(),
                 m.forces_N.size(), o->topology, m.bands.size(), o->a.out);
      return kExitOk;
    });
  });
}

void AddCvVibration(CLI::App& model) {
  auto a = std::make_shared<VibArgs>();
  auto ts = std::make_shared<std::string>("0.04,0.08,0.12");
  auto tf = std::make_shared<std::string>("0.54,1.18,1.91");
  auto json_out = std::make_shared<bool>(false);
  auto seed = std::make_shared<std::uint64_t>(1);
  auto plots = std::make_shared<std::string>();
  auto kind = std::make_shared<std::string>("lpc");
  auto epochs = std::make_shared<int>(40);
  auto* cmd = model.add_subcommand(
      "cv-vibration",
      "Cross-validation as dissertation ch. III.4: fit on the training speeds x forces, then\n"
      "E_s (eq. 3.1) of the renderer's interpolated synthesis at every recorded condition;\n"
      "--plots draws measured vs synthesized spectra like Figs. 3.5/3.6.");
  AddVibOptions(cmd, *a);
  cmd->add_option("--train-speeds", *ts, "Training speeds [m/s], comma-separated")->capture_default_str();
  cmd->add_option("--train-forces", *tf, "Training forces [N], comma-separated")->capture_default_str();
  cmd->add_option("--seed", *seed, "Synthesis seed")->capture_default_str();
  cmd->add_option("--plots", *plots, "Write measured vs synthesized spectra per condition here (SVG and PNG)");
  cmd->add_flag("--json", *json_out, "Print {\"conditions\":[...],\"mean_es_train\",\"mean_es_test\"}");
  cmd->add_option("--model-kind", *kind,
                  "lpc: the AR bank; neural-unified: Γ_U; neural-decomposed: Γ_D (dissertation ch. III.3, "
                  "Fig. 3.7: run all three on the same recordings for one E_s table)")
      ->check(CLI::IsMember({"lpc", "neural-unified", "neural-decomposed"}))
      ->capture_default_str();
  cmd->add_option("--epochs", *epochs, "Neural models: maximum training epochs")->capture_default_str()->check(CLI::Range(1, 10000));
  cmd->callback([=] {
    RunGuarded([&] {
      const auto recs = modeling::LoadRecordings(a->recordings);
      modeling::CvResult cv;
      if (*kind == "lpc") {
        cv = modeling::CrossValidate(recs, ParseList(*ts, "--train-speeds"), ParseList(*tf, "--train-forces"), VibOptions(*a), *seed);
      } else {
        modeling::NeuralFitOptions no;
        no.topology = *kind == "neural-unified" ? renderer::NeuralTopology::kUnified : renderer::NeuralTopology::kDecomposed;
        no.preprocess = VibOptions(*a);
        no.train.max_epochs = *epochs;
        no.train.seed = *seed;
        cv = modeling::CrossValidateNeural(recs, ParseList(*ts, "--train-speeds"), ParseList(*tf, "--train-forces"), no, *seed);
      }
      if (!plots->empty()) {
        std::filesystem::create_directories(*plots);
        for (const auto& r : cv.rows) {
          stats::LinePlot lp;
          lp.title = fmt::format("{:.0f} mm/s, {:.2f} N ({}), E_s = {:.3f}", r.speed_mps * 1e3, r.force_N,
                                 r.train ? "training" : "held out", r.es);
          lp.x_label = "frequency [Hz]";
          lp.y_label = "|A(f)|";
          lp.log_y = true;
          for (std::size_t k = 0; k < r.measured_spectrum.size(); ++k)
            lp.x.push_back(static_cast<double>(k) * VibOptions(*a).model_rate_hz / (2.0 * static_cast<double>(r.measured_spectrum.size() - 1)));
          lp.series = {{"measured", r.measured_spectrum}, {"synthesized", r.synthesized_spectrum}};
          stats::DrawLinePlot(lp, (std::filesystem::path(*plots) / fmt::format("spectrum_v{:.0f}_f{:.0f}", r.speed_mps * 1e3, r.force_N * 100)).string());
        }
      }
      if (*json_out) {
        nlohmann::json rows = nlohmann::json::array();
        for (const auto& r : cv.rows)
          rows.push_back({{"speed_mps", r.speed_mps}, {"force_N", r.force_N}, {"split", r.train ? "train" : "test"}, {"es", r.es}});
        fmt::print("{}\n", nlohmann::json{{"model_kind", *kind}, {"conditions", rows}, {"mean_es_train", cv.mean_es_train},
                                          {"mean_es_test", cv.mean_es_test}, {"order", cv.order}}.dump(2));
        return kExitOk;
      }
      fmt::print("{:>10} {:>9} {:>6} {:>7}\n", "speed m/s", "force N", "split", "E_s");
      for (const auto& r : cv.rows)
        fmt::print("{:>10.3f} {:>9.3f} {:>6} {:>7.3f}\n", r.speed_mps, r.force_N, r.train ? "train" : "test", r.es);
      const bool any_test = std::any_of(cv.rows.begin(), cv.rows.end(), [](const auto& r) { return !r.train; });
      fmt::print("mean E_s ({}): training {:.3f}, held-out {}{}\n", *kind, cv.mean_es_train,
                 any_test ? fmt::format("{:.3f}", cv.mean_es_test) : std::string("n/a (no held-out conditions)"),
                 *kind == "lpc" ? fmt::format(" (AR order {})", cv.order) : std::string());
      return kExitOk;
    });
  });
}

void AddCutoff(CLI::App& model) {
  auto file = std::make_shared<std::string>();
  auto lo = std::make_shared<double>(50), hi = std::make_shared<double>(150), step = std::make_shared<double>(10);
  auto json_out = std::make_shared<bool>(false);
  auto* cmd = model.add_subcommand(
      "cutoff",
      "Stationarity cut-off (dissertation ch. III.5): the smallest high-pass cut-off in the range\n"
      "whose filtered recording rejects a unit root (augmented Dickey-Fuller, 5 %). It becomes\n"
      "the material's hybrid filter f_c.");
  cmd->add_option("--recording", *file, "Measurement CSV v1 with acc_mps2")->required();
  cmd->add_option("--from", *lo, "Lowest cut-off [Hz]")->capture_default_str();
  cmd->add_option("--to", *hi, "Highest cut-off [Hz]")->capture_default_str();
  cmd->add_option("--step", *step, "Step [Hz]")->capture_default_str();
  cmd->add_flag("--json", *json_out, "Print the result and every cut-off tried as JSON");
  cmd->callback([=] {
    RunGuarded([&] {
      const auto r = modeling::LoadRecording(*file);
      const auto c = modeling::StationarityCutoff(r.acc, r.rate_hz, *lo, *hi, *step);
      if (*json_out) {
        nlohmann::json tried = nlohmann::json::array();
        for (const auto& [fc, adf] : c.tried)
          tried.push_back({{"cutoff_hz", fc}, {"adf", adf.statistic}, {"critical_5pct", adf.critical_5pct},
                           {"lags", adf.lags}, {"stationary", adf.rejects_unit_root}});
        fmt::print("{}\n", nlohmann::json{{"found", c.found}, {"cutoff_hz", c.found ? nlohmann::json(c.cutoff_hz) : nlohmann::json()},
                                          {"tried", tried}}.dump(2));
      } else if (c.found) {
        fmt::print("f_c = {:.1f} Hz (ADF {:.2f} < {:.2f} at 5 %)\n", c.cutoff_hz, c.tried.back().second.statistic,
                   c.tried.back().second.critical_5pct);
      } else {
        fmt::print("no cut-off in {:.0f}-{:.0f} Hz makes the recording stationary\n", *lo, *hi);
      }
      return c.found ? kExitOk : kExitFailure;
    });
  });
}

// Writes a whole text file; errors name the file.
void WriteModelText(const std::string& path, const std::string& text) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw std::runtime_error(path + ": cannot write");
  const bool ok = std::fputs(text.c_str(), f) >= 0;
  if (std::fclose(f) != 0 || !ok) throw std::runtime_error(path + ": write failed");
}

void AddFitContact(CLI::App& model) {
  struct O {
    std::string measurement, pokes, out;
    bool json = false;
  };
  auto o = std::make_shared<O>();
  auto* cmd = model.add_subcommand(
      "fit-contact",
      "Identify friction and stiffness on a flat sample with its surface at z = 0 (dissertation\n"
      "ch. IV.3) with the workbench's engine: vector Dahl friction with Coulomb and viscous terms\n"
      "replayed over the measured 2-D path (strokes in any direction), started by Algorithm 1 and\n"
      "refined jointly by Ceres; Hunt-Crossley K, B, n on pokes (samples above 2 N discarded).\n"
      "Pokes are the samples without sliding in --measurement, or a separate --pokes file.\n"
      "Uncertainties: cluster jackknife over 3 s clusters of blocks, 95 % intervals. Prints each\n"
      "solve's termination, iterations, cost and parameters at bounds; exits 1 when a fit is not\n"
      "usable. Writes a material model (effects, [contact], [friction]) for `model build`.");
  cmd->add_option("--measurement", o->measurement, "Strokes (and pokes): measurement CSV v1")->required();
  cmd->add_option("--pokes", o->pokes, "Pokes in a separate measurement CSV v1");
  cmd->add_option("-o,--out", o->out, "Material model TOML to write ([contact], [friction], effects)")->required();
  cmd->add_flag("--json", o->json,
                "Print {\"hunt_crossley\":{K,B,n},\"dahl\":{kappa,mu_k,mu_b},\"uncertainty\":{...},\"fit\":{friction,"
                "normal_force},\"usable\"}");
  cmd->callback([o] {
    RunGuarded([&] {
      const auto m = ReadMeasurementCsv(o->measurement);
      Measurement pokes;
      if (!o->pokes.empty()) pokes = ReadMeasurementCsv(o->pokes);
      const auto f = modeling::FitContact(m, o->pokes.empty() ? nullptr : &pokes);
      // Written through the model types: the renderer's material, effects included.
      renderer::MaterialModel mm;
      mm.name = std::filesystem::path(o->out).stem().string();
      mm.effects = modeling::ContactEffects();
      mm.contact.texture = {f.K.value, f.B.value, f.n.value};
      mm.contact.base = {0, 0, 1};
      mm.contact.layer_thickness_m = 0.005;  // no base felt: thicker than any measured penetration
      mm.friction = {f.kappa_N_per_m.value, f.mu_k.value, f.mu_b_Ns_per_m.value};
      auto ci = [](const char* k, const modeling::Estimate& e) {
        return fmt::format("#   {:14s} {:.6g} +- {:.3g} (95 %: {:.6g} .. {:.6g})\n", k, e.value, e.sd, e.lo95, e.hi95);
      };
      std::string text = fmt::format("# Fitted by hapticlab model fit-contact from {} (SI units).\n# Uncertainty: {}.\n",
                                     o->measurement, f.uncertainty_method);
      text += ci("texture_K", f.K) + ci("texture_B", f.B) + ci("texture_n", f.n) + ci("kappa_N_per_m", f.kappa_N_per_m) +
              ci("mu_k", f.mu_k) + ci("mu_b_Ns_per_m", f.mu_b_Ns_per_m);
      text += renderer::MaterialToToml(mm);
      WriteModelText(o->out, text);
      renderer::LoadMaterial(o->out);  // what was written is a loadable material
      if (o->json) {
        auto est = [](const modeling::Estimate& e) {
          return nlohmann::json{{"value", e.value}, {"sd", e.sd}, {"lo95", e.lo95}, {"hi95", e.hi95}};
        };
        fmt::print("{}\n", nlohmann::json{
                               {"hunt_crossley", {{"K", f.K.value}, {"B", f.B.value}, {"n", f.n.value},
                                                  {"K1mm_N", f.K1mm_N.value}, {"B1mm", f.B1mm_Ns_per_m.value}}},
                               {"dahl", {{"kappa", f.kappa_N_per_m.value}, {"mu_k", f.mu_k.value}, {"mu_b", f.mu_b_Ns_per_m.value}}},
                               {"uncertainty", {{"K", est(f.K)}, {"B", est(f.B)}, {"n", est(f.n)}, {"K1mm_N", est(f.K1mm_N)},
                                                {"B1mm", est(f.B1mm_Ns_per_m)}, {"kappa", est(f.kappa_N_per_m)},
                                                {"mu_k", est(f.mu_k)}, {"mu_b", est(f.mu_b_Ns_per_m)}}},
                               {"uncertainty_method", f.uncertainty_method},
                               {"residual_rms_N", {{"hunt_crossley", f.normal_rms_N}, {"dahl", f.friction_rms_N}}},
                               {"samples", {{"strokes", f.stroke_samples}, {"pokes", f.poke_samples}}},
                               {"poke_source", f.poke_source},
                               {"algorithm1", {{"passes", f.algorithm1.passes}, {"converged", f.algorithm1.converged},
                                               {"kappa", f.algorithm1.kappa_N_per_m}, {"mu_k", f.algorithm1.mu_k},
                                               {"mu_b", f.algorithm1.mu_b_Ns_per_m}}},
                               {"fit", {{"friction", FitSummaryJson(f.friction_summary)},
                                        {"normal_force", FitSummaryJson(f.normal_summary)}}},
                               {"usable", f.IsUsable()},
                               {"out", o->out}}
                               .dump(2));
      } else {
        auto pm = [](const modeling::Estimate& e) {
          return fmt::format("{:.5g} +- {:.2g} [{:.5g}, {:.5g}]", e.value, e.sd, e.lo95, e.hi95);
        };
        fmt::print("Hunt-Crossley ({} samples <= 2 N from {}): K = {} N/m^n, B = {} N s/m^(n+1), n = {}; rms {:.4f} N\n",
                   f.poke_samples, f.poke_source, pm(f.K), pm(f.B), pm(f.n), f.normal_rms_N);
        fmt::print("Dahl ({} samples; Algorithm 1: {} passes{}, kappa {:.4g}, mu_k {:.4f}, mu_b {:.4f}): kappa = {} N/m, "
                   "mu_k = {}, mu_b = {} N s/m; rms {:.4f} N\n",
                   f.stroke_samples, f.algorithm1.passes, f.algorithm1.converged ? "" : ", not converged",
                   f.algorithm1.kappa_N_per_m, f.algorithm1.mu_k, f.algorithm1.mu_b_Ns_per_m, pm(f.kappa_N_per_m),
                   pm(f.mu_k), pm(f.mu_b_Ns_per_m), f.friction_rms_N);
        fmt::print("{}\n{}\n", FitSummaryLine(f.friction_summary), FitSummaryLine(f.normal_summary));
        fmt::print("uncertainty: {}\nwrote {}\n", f.uncertainty_method, o->out);
      }
      if (!f.IsUsable()) {
        fmt::print(stderr, "fit-contact: a fit is not usable (see the fit lines); {} was written for inspection\n", o->out);
        return kExitFailure;
      }
      return kExitOk;
    });
  });
}

// The photometric command's outputs (normals, albedo) and its options' checks.
namespace photometric_out {

std::string Extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  for (auto& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

bool IsTiff(const std::string& path) { return Extension(path) == ".tif" || Extension(path) == ".tiff"; }

// Refuses an output name whose extension has no writer here, before any work.
void CheckImageOutput(const std::string& path, const std::string& option) {
  if (!path.empty() && !IsTiff(path) && Extension(path) != ".png")
    throw InputError("", 0, option, path + ": .png (8/16-bit) or .tif/.tiff (32-bit float) expected");
}

// Normals: PNG as 8-bit RGB = round(127.5 (n + 1)), TIFF as float RGB = (x, y, z); zero
// outside the mask. `y_up` writes y upwards (the frame of y-up lights).
void WriteNormals(const std::string& path, const modeling::PhotometricResult& r, bool y_up) {
  const bool tiff = IsTiff(path);
  cv::Mat m(r.height, r.width, tiff ? CV_32FC3 : CV_8UC3, cv::Scalar::all(0));
  for (int i = 0; i < r.height; ++i)
    for (int j = 0; j < r.width; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * static_cast<std::size_t>(r.width) + static_cast<std::size_t>(j);
      if (!r.mask[k]) continue;
      const Eigen::Vector3f n(r.normals[k].x(), y_up ? -r.normals[k].y() : r.normals[k].y(), r.normals[k].z());
      if (tiff) {
        m.at<cv::Vec3f>(i, j) = cv::Vec3f(n.z(), n.y(), n.x());  // OpenCV's B, G, R: the file holds x, y, z
      } else {
        auto q = [](float c) { return static_cast<unsigned char>(std::clamp(std::lround(127.5 * (static_cast<double>(c) + 1)), 0L, 255L)); };
        m.at<cv::Vec3b>(i, j) = cv::Vec3b(q(n.z()), q(n.y()), q(n.x()));
      }
    }
  // Uncompressed: OpenCV 4.6 writes 3-channel float TIFF as lossy LogLuv (SGILOG) by default.
  const std::vector<int> params = tiff ? std::vector<int>{cv::IMWRITE_TIFF_COMPRESSION, 1} : std::vector<int>{};
  if (!cv::imwrite(path, m, params)) throw std::runtime_error(path + ": cannot write");
}

// Albedo: TIFF as float (|b|, relative to the mean light), PNG as 16-bit scaled so that the
// largest albedo is 65535.
void WriteAlbedo(const std::string& path, const modeling::PhotometricResult& r) {
  cv::Mat f(r.height, r.width, CV_32F, const_cast<float*>(r.albedo.data()));
  if (IsTiff(path)) {
    if (!cv::imwrite(path, f)) throw std::runtime_error(path + ": cannot write");
    return;
  }
  const float mx = *std::max_element(r.albedo.begin(), r.albedo.end());
  cv::Mat u;
  f.convertTo(u, CV_16U, mx > 0 ? 65535.0 / static_cast<double>(mx) : 0.0);
  if (!cv::imwrite(path, u)) throw std::runtime_error(path + ": cannot write");
}

}  // namespace photometric_out

void AddPhotometric(CLI::App& model) {
  struct O {
    std::string images, lights = "dome", image_list, reference, mask, out, csv, tiff, normals, albedo, integration = "auto",
                                         rejection = "residual";
    double pitch = 0, shadow_fraction = 0.05, outlier_sigmas = 3, noise_floor = 1e-3, specular_fraction = 0.1;
    int min_lights = 4;
    bool y_up = false;
  };
  auto o = std::make_shared<O>();
  auto* cmd = model.add_subcommand(
      "photometric",
      "Height map from photographs under known lights (photometric stereo, ch. IV.2): albedo and\n"
      "normals by alternating least squares on the Lambertian model, each pixel's shadowed and\n"
      "specular readings rejected from its own fit residuals, integrated by Frankot-Chellappa or a\n"
      "Poisson solve. Writes HEIGHT.f32 (the renderer's raw float32 metres) and HEIGHT.f32.toml\n"
      "(its [geometry] table for `model build`).\n"
      "Image frame: x along the columns (rightwards), y along the rows (DOWNWARDS, row 0 first),\n"
      "z up out of the sample towards the camera; light directions point towards the lights.\n"
      "Lights given with y up (x right, y up, z towards the camera) need --lights-y-up; a warning\n"
      "is printed when the normals look mirrored.");
  cmd->add_option("--images", o->images, "Folder of the images (any format OpenCV reads, plus TGA; linear response)")->required();
  cmd->add_option("--lights", o->lights,
                  "Lights file, one light per line, comma and/or whitespace separated: 'file elevation_deg\n"
                  "azimuth_deg' (azimuth from +x towards +y), 'file lx ly lz', or 'lx ly lz' with --image-list;\n"
                  "optional first line with the count, optional header line; '#' lines ignored. Or 'dome'\n"
                  "for the dissertation's 30-light dome with images light_00.png ... light_29.png")->capture_default_str();
  cmd->add_option("--image-list", o->image_list, "File names of the images, one per line in the lights' order (e.g. DiLiGenT's filenames.txt)");
  cmd->add_flag("--lights-y-up", o->y_up, "The lights (and the normals written) use y up instead of y down the rows");
  cmd->add_option("--reference", o->reference, "Folder of white-reference images (same names) for the radiance maps");
  cmd->add_option("--mask", o->mask, "Mask image (any format above; non-zero = inside): outside pixels are neither solved nor integrated");
  cmd->add_option("--pitch-m", o->pitch, "Pixel pitch on the sample [m]")->required()->check(CLI::PositiveNumber);
  cmd->add_option("--integration", o->integration,
                  "frankot-chellappa (periodic, FFT; whole image only), poisson (Neumann boundary: DCT on the\n"
                  "whole image, sparse solve on a mask), or auto (poisson with --mask, else frankot-chellappa)")
      ->check(CLI::IsMember({"auto", "frankot-chellappa", "poisson"}))->capture_default_str();
  cmd->add_option("--rejection", o->rejection,
                  "residual (per pixel, from its Lambertian fit residuals) or brightest (the fixed rule:\n"
                  "drop the brightest --specular-fraction of each pixel's lights)")
      ->check(CLI::IsMember({"residual", "brightest"}))->capture_default_str();
  cmd->add_option("--outlier-sigmas", o->outlier_sigmas,
                  "residual rule: a reading is an outlier beyond this many robust SDs of all residuals")
      ->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--shadow-fraction", o->shadow_fraction,
                  "readings darker than this fraction of the pixel's fitted brightness facing the light are\n"
                  "shadows (brightest rule: of the pixel's brightest reading)")
      ->check(CLI::Range(0.0, 1.0))->capture_default_str();
  cmd->add_option("--noise-floor", o->noise_floor, "residual rule: least residual SD, fraction of the facing brightness")
      ->check(CLI::Range(0.0, 1.0))->capture_default_str();
  cmd->add_option("--min-lights", o->min_lights, "residual rule: outlier rejection keeps at least this many lights")
      ->check(CLI::Range(3, 1000))->capture_default_str();
  cmd->add_option("--specular-fraction", o->specular_fraction, "brightest rule only: fraction of each pixel's lights dropped")
      ->check(CLI::Range(0.0, 1.0))->capture_default_str();
  cmd->add_option("-o,--out", o->out, "Height map to write (.f32)")->required();
  cmd->add_option("--csv", o->csv, "Also write heights [m] as CSV (one image row per line)");
  cmd->add_option("--tiff", o->tiff, "Also write heights [m] as a 32-bit float TIFF");
  cmd->add_option("--normals", o->normals,
                  "Also write the normals: .png as 8-bit RGB = round(127.5 (n + 1)), .tif/.tiff as 32-bit float\n"
                  "RGB = (x, y, z); zero outside the mask");
  cmd->add_option("--albedo", o->albedo, "Also write the albedo: .tif/.tiff as 32-bit float, .png as 16-bit scaled to its maximum");
  cmd->callback([o] {
    RunGuarded([&] {
      photometric_out::CheckImageOutput(o->normals, "--normals");
      photometric_out::CheckImageOutput(o->albedo, "--albedo");
      if (!o->mask.empty() && o->integration == "frankot-chellappa")
        throw InputError("", 0, "--integration", "frankot-chellappa integrates the whole image; with --mask use poisson");
      auto lights = modeling::LoadLights(o->lights, o->y_up);
      if (!o->image_list.empty()) modeling::ApplyImageList(o->image_list, lights);
      for (const auto& l : lights)
        if (l.file.empty()) throw InputError(o->lights, l.line, "file", "no image name for this light: give --image-list");
      const auto images = modeling::ReadImages(o->images, lights);
      modeling::ImageStack ref;
      if (!o->reference.empty()) ref = modeling::ReadImages(o->reference, lights);
      if (!o->reference.empty() && (ref.width != images.width || ref.height != images.height))
        throw InputError(o->reference, 0, "", "the reference images differ in size from the images");
      modeling::PhotometricOptions po;
      po.pitch_m = o->pitch;
      po.integration = o->integration == "poisson" || (o->integration == "auto" && !o->mask.empty())
                           ? modeling::Integration::kPoisson
                           : modeling::Integration::kFrankotChellappa;
      po.rejection = o->rejection == "brightest" ? modeling::Rejection::kBrightest : modeling::Rejection::kResidual;
      po.shadow_fraction = o->shadow_fraction;
      po.outlier_sigmas = o->outlier_sigmas;
      po.noise_floor = o->noise_floor;
      po.min_lights = o->min_lights;
      po.specular_fraction = o->specular_fraction;
      if (!o->mask.empty()) po.mask = modeling::ReadMask(o->mask, images.width, images.height);
      const bool tty = isatty(2);
      auto progress = [&](double f) {
        if (tty) fmt::print(stderr, "\rphotometric stereo [{:<40}] {:3.0f} %", std::string(static_cast<std::size_t>(40 * f), '#'), 100 * f);
      };
      const auto r = modeling::PhotometricStereo(images, lights, po, o->reference.empty() ? nullptr : &ref, progress);
      if (tty) fmt::print(stderr, "\n");
      float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
      for (std::size_t k = 0; k < r.height_m.size(); ++k)
        if (r.mask[k]) {
          lo = std::min(lo, r.height_m[k]);
          hi = std::max(hi, r.height_m[k]);
        }
      if (!(hi >= lo)) throw InputError(o->mask, 0, "", "the mask has no pixel inside");
      std::vector<float> h(r.height_m);
      for (auto& v : h) v -= lo;  // heights above the lowest point (outside the mask: 0)
      renderer::HeightMap(r.width, r.height, o->pitch, h).SaveRawF32(o->out);
      {
        FILE* g = std::fopen((o->out + ".toml").c_str(), "w");
        if (!g) throw std::runtime_error(o->out + ".toml: cannot write");
        std::fputs(fmt::format("[geometry]\nkind = \"file\"\nfile = \"{}\"\nwidth = {}\nheight = {}\npitch_m = {:.10g}\n",
                               std::filesystem::path(o->out).filename().string(), r.width, r.height, o->pitch).c_str(), g);
        std::fclose(g);
      }
      if (!o->csv.empty()) {
        FILE* c = std::fopen(o->csv.c_str(), "w");
        if (!c) throw std::runtime_error(o->csv + ": cannot write");
        for (int i = 0; i < r.height; ++i)
          for (int j = 0; j < r.width; ++j)
            std::fprintf(c, "%.9g%c", h[static_cast<std::size_t>(i * r.width + j)], j + 1 == r.width ? '\n' : ',');
        std::fclose(c);
      }
      if (!o->tiff.empty()) {
        cv::Mat m(r.height, r.width, CV_32F, h.data());
        if (!cv::imwrite(o->tiff, m)) throw std::runtime_error(o->tiff + ": cannot write TIFF");
      }
      if (!o->normals.empty()) photometric_out::WriteNormals(o->normals, r, o->y_up);
      if (!o->albedo.empty()) photometric_out::WriteAlbedo(o->albedo, r);
      const std::size_t inside = static_cast<std::size_t>(std::count(r.mask.begin(), r.mask.end(), 1));
      fmt::print("{}x{} height map, range {:.3g} m -> {} (+ {}.toml)\n", r.width, r.height, static_cast<double>(hi - lo), o->out, o->out);
      fmt::print("{} pixels solved{}{}; residual SD {:.3g} of the brightness facing a light; readings dropped: "
                 "{:.1f} % bright (highlights), {:.1f} % dark (shadows)\n",
                 inside - r.unsolved_pixels, o->mask.empty() ? "" : " inside the mask",
                 r.unsolved_pixels ? fmt::format(" ({} more with fewer than 3 usable lights)", r.unsolved_pixels) : "",
                 r.residual_sd, 100 * r.dropped_bright, 100 * r.dropped_dark);
      if (r.axis_flip_suspected)
        fmt::print(stderr,
                   "warning: the normals are {:.1f}x less integrable than with one image axis mirrored: the lights' frame\n"
                   "  looks mirrored ({}). Frame: x along the columns, y {} the rows, z towards the camera.\n",
                   r.mirrored_curl_ratio, o->y_up ? "lights written with y down? drop --lights-y-up" : "lights written with y up? pass --lights-y-up",
                   o->y_up ? "up" : "down");
      return kExitOk;
    });
  });
}

void AddBuild(CLI::App& model) {
  struct O {
    std::string name, height, contact, vibration, out;
    double cutoff = 100;
  };
  auto o = std::make_shared<O>();
  auto* cmd = model.add_subcommand(
      "build", "Assemble a complete material model from a height map (its .f32.toml from `model photometric`),\n"
               "a contact fit (`model fit-contact`) and a vibration bank (`model fit-vibration`). Every\n"
               "fitted effect and parameter of the parts is kept (the contact fit's effects, e.g.\n"
               "hc-exponent, and the bank's vibration-speed/vibration-force); the bank is written inline.");
  cmd->add_option("--name", o->name, "Material name")->required();
  cmd->add_option("--height", o->height, "Geometry TOML written beside the height map (HEIGHT.f32.toml)")->required();
  cmd->add_option("--contact", o->contact, "Contact fit from fit-contact (a material TOML, or [contact] and [friction])")
      ->required();
  cmd->add_option("--vibration", o->vibration, "BANK.toml from fit-vibration")->required();
  cmd->add_option("--cutoff-hz", o->cutoff, "Hybrid filter cut-off f_c [Hz] (see `model cutoff`)")->capture_default_str();
  cmd->add_option("-o,--out", o->out, "Material model to write (.toml)")->required();
  cmd->callback([o] {
    RunGuarded([&] {
      namespace fs = std::filesystem;
      const auto outdir = fs::absolute(o->out).parent_path();
      auto rel = [&](const std::string& p) { return fs::relative(fs::absolute(p), outdir).string(); };
      auto quoted = [](const std::string& p) { return nlohmann::json(p).dump(); };
      // Each part is read through the renderer's material parser (its own file named in errors).
      // Parts without the tables a material requires get neutral ones (not used).
      auto parse = [](std::string text, const std::string& path, bool contact_part) {
        static const std::regex kName(R"((^|\n)[ \t]*name[ \t]*=)");
        if (!contact_part) text = "[contact]\ntexture_K = 1.0\n\n[friction]\nkappa_N_per_m = 1.0\nmu_k = 0.0\n\n" + text;
        if (!std::regex_search(text, kName)) text = "name = \"part\"\n" + text;
        return renderer::ParseMaterial(text, path);
      };
      renderer::MaterialModel mm = parse(ReadTextFile(o->contact, "contact fit"), o->contact, true);
      const auto g = parse(ReadTextFile(o->height, "geometry table"), o->height, false);
      const auto v = parse("[vibration]\nfile = " + quoted(fs::absolute(o->vibration).string()) + "\n", o->vibration, false);
      mm.name = o->name;
      mm.source_path.clear();
      mm.geometry = g.geometry;
      mm.vibration = v.vibration;
      mm.hybrid_cutoff_hz = o->cutoff;
      if (mm.effects.empty()) {
        // A contact part without an effect list: the effects its parameters say were fitted.
        mm.effects = {"coulomb", "dahl"};
        if (mm.friction.mu_b_Ns_per_m > 0) mm.effects.push_back("viscous");
        if (mm.contact.texture.B > 0) mm.effects.push_back("hc-damping");
        if (mm.contact.texture.n != 1) mm.effects.push_back("hc-exponent");
      }
      if (!mm.vibration.empty())
        for (const char* e : {"vibration-speed", "vibration-force"})
          if (std::find(mm.effects.begin(), mm.effects.end(), e) == mm.effects.end()) mm.effects.push_back(e);
      // The geometry by reference to its .f32, relative to the model.
      const auto f32 = (fs::absolute(o->height).parent_path() / fs::path(o->height).stem()).string();
      WriteModelText(o->out, renderer::MaterialToToml(mm, rel(f32)));
      const auto m = renderer::LoadMaterial(o->out);  // validates the assembled model
      fmt::print("{}: {} ({}x{} map, {} vibration cells, f_c {:.0f} Hz; effects: {})\n", o->out, m.name, m.geometry->width(),
                 m.geometry->height(), m.vibration.cells.size(), m.hybrid_cutoff_hz, fmt::join(m.effects, ", "));
      return kExitOk;
    });
  });
}

}  // namespace

void RegisterModel(CLI::App& app) {
  auto* model = app.add_subcommand(
      "model", "Material models: check, render offline, stability energy, import Penn XML,\n"
               "fit and cross-validate vibration banks, find the stationarity cut-off.");
  model->require_subcommand(1);
  AddCheck(*model);
  AddRender(*model);
  AddEnergy(*model);
  AddImportPenn(*model);
  AddFitVibration(*model);
  AddFitNeural(*model);
  AddCvVibration(*model);
  AddCutoff(*model);
  AddFitContact(*model);
  AddPhotometric(*model);
  AddBuild(*model);
}

}  // namespace hapticlab::cli
