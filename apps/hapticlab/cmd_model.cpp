// hapticlab model: check, render, energy, import and build material models; the fitting
// commands live in cmd_model_vibration.cpp, cmd_model_contact.cpp and cmd_model_photometric.cpp.

#include "cmd_model.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <limits>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "cli_common.hpp"
#include "commands.hpp"
#include "fit_summary_json.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/measurement.hpp"
#include "hapticlab/modeling/contact.hpp"
#include "hapticlab/modeling/neural.hpp"
#include "hapticlab/modeling/photometric.hpp"
#include "hapticlab/modeling/vibration.hpp"
#include "hapticlab/modeling/workbench_io.hpp"
#include "hapticlab/renderer/energy.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/renderer/penn_import.hpp"
#include "hapticlab/runner/offline.hpp"
#include "hapticlab/stats/plot.hpp"

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
      nlohmann::json j = {
          {"name", m.name},
          {"effects", m.effects},
          {"texture",
           {{"K", m.contact.texture.K}, {"B", m.contact.texture.B}, {"n", m.contact.texture.n}}},
          {"friction",
           {{"kappa_N_per_m", m.friction.kappa_N_per_m},
            {"mu_k", m.friction.mu_k},
            {"mu_b_Ns_per_m", m.friction.mu_b_Ns_per_m}}},
          {"height_map",
           {{"width", m.geometry->width()},
            {"height", m.geometry->height()},
            {"pitch_m", m.geometry->pitch_m()},
            {"range_m", m.geometry->max_m() - m.geometry->min_m()}}},
          {"vibration",
           {{"cells", m.vibration.cells.size()},
            {"order", m.vibration.order()},
            {"sample_rate_hz", m.vibration.sample_rate_hz}}},
          {"hybrid_cutoff_hz", m.hybrid_cutoff_hz}};
      if (*json)
        PrintJson(j);
      else
        fmt::print("{}: ok\n{}\n", *path, JsonText(j, 2));
      return kExitOk;
    });
  });
}

// render --force-source: the normal force the vibration model reads.
enum class ForceSource { kAuto, kTrajectory, kModel };
inline constexpr EnumTable<ForceSource, 3> kForceSourceNames{
    {{ForceSource::kAuto, "auto"},
     {ForceSource::kTrajectory, "trajectory"},
     {ForceSource::kModel, "model"}}};

struct RenderArgs {
  std::string model, trajectory, out, vib_out, algorithm = "fric2";
  ForceSource force_source = ForceSource::kAuto;
  double force_rate = 1000, vib_rate = 10000, max_force = 8;
  bool no_vibration = false, no_filter = false;
  std::uint64_t seed = 1;
};

// The rendered rows (and with --vibration-out every vibration sample) as CSV files.
void WriteRenderCsv(const RenderArgs& o, const runner::OfflineResult& res, const Measurement& traj,
                    const renderer::RenderOptions& ro) {
  std::string csv =
      "t_s,fx_N,fy_N,fz_N,cmd_fx_N,cmd_fy_N,cmd_fz_N,normal_N,friction_N,speed_mps,in_contact,"
      "fault,acc_mps2\n";
  for (const auto& r : res.rows)
    fmt::format_to(
        std::back_inserter(csv),
        "{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{},{},{:.9g}\n",
        r.t_s, r.force_N.x(), r.force_N.y(), r.force_N.z(), r.command_N.x(), r.command_N.y(),
        r.command_N.z(), r.normal_N, r.friction_N, r.speed_mps, r.in_contact ? 1 : 0,
        r.fault ? 1 : 0, r.acc_mps2);
  WriteTextFile(o.out, csv);
  if (!o.vib_out.empty()) {
    std::string vib = "t_s,acc_mps2\n";
    for (std::size_t k = 0; k < res.vibration_mps2.size(); ++k)
      fmt::format_to(std::back_inserter(vib), "{:.9g},{:.9g}\n",
                     traj.rows.front().t_s + static_cast<double>(k) / ro.vibration_rate_hz,
                     res.vibration_mps2[k]);
    WriteTextFile(o.vib_out, vib);
  }
}

int RunRender(const RenderArgs& o) {
  const auto m = renderer::LoadMaterial(o.model);
  const auto traj = ReadMeasurementCsv(o.trajectory, {.kinematics_only = true});
  if (traj.rows.size() < 2) throw InputError(o.trajectory, 0, "", "needs at least two samples");
  renderer::RenderOptions ro;
  ro.algorithm = renderer::ParseForceAlgorithm(o.algorithm);
  ro.vibration = !o.no_vibration;
  ro.hybrid_filter = !o.no_filter;
  ro.vibration_rate_hz = o.vib_rate;
  ro.max_force_N = o.max_force;
  ro.seed = o.seed;
  // The force loop runs at the trajectory's own rate.
  ro.force_rate_hz =
      static_cast<double>(traj.rows.size() - 1) / (traj.rows.back().t_s - traj.rows.front().t_s);
  ro.stale_after_s = 1e9;  // offline: samples are never stale
  if (o.force_source == ForceSource::kTrajectory && !traj.has_forces)
    throw InputError(o.trajectory, 0, "fz_N",
                     "--force-source trajectory needs force columns (fx_N, fy_N, fz_N)");
  runner::OfflineOptions oo;
  oo.measured_normal_force = o.force_source != ForceSource::kModel && traj.has_forces;
  const auto res = runner::RenderOffline(m, ro, traj, oo);
  WriteRenderCsv(o, res, traj, ro);
  fmt::print(stderr,
             "rendered {} force ticks at {:.0f} Hz and {} vibration samples (vibration force: "
             "{}) -> {}\n",
             res.rows.size(), ro.force_rate_hz, res.vibration_mps2.size(),
             oo.measured_normal_force ? "the trajectory's fz_N" : "the rendered normal force",
             o.out);
  return kExitOk;
}

void AddRender(CLI::App& model) {
  auto o = std::make_shared<RenderArgs>();
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
  cmd->add_option("--vibration-out", o->vib_out,
                  "Also write every vibration sample (CSV t_s,acc_mps2)");
  cmd->add_option("--algorithm", o->algorithm, "Force algorithm")
      ->check(CLI::IsMember({"wall", "norm", "fric1", "fric2", "none"}))
      ->capture_default_str();
  cmd->add_option("--vibration-rate", o->vib_rate, "Vibration loop rate [Hz]")
      ->capture_default_str();
  cmd->add_option("--max-force", o->max_force, "Device force limit [N]")->capture_default_str();
  AddEnumOption(cmd, "--force-source", o->force_source, kForceSourceNames,
                "Normal force of the vibration model: auto (the trajectory's when it has forces),\n"
                "trajectory (required), model (the rendered normal force)");
  cmd->add_flag("--no-vibration", o->no_vibration, "Force only");
  cmd->add_flag("--no-hybrid-filter", o->no_filter, "Do not low/high-pass at the model's f_c");
  cmd->add_option("--seed", o->seed, "Vibration noise seed")->capture_default_str();
  cmd->callback([o] { RunGuarded([&] { return RunRender(*o); }); });
}

struct EnergyArgs {
  std::string algorithm = "norm", sine, model;
  double dx = 1e-4, dz = 0, stiffness = 1000, mu = 0;
  int steps = 20000;
  bool json = false;
};

// --sine AMPLITUDE_M,WAVELENGTH_M: both positive.
std::pair<double, double> ParseSine(const std::string& sine) {
  auto comma = sine.find(',');
  double a = 0, l = 0;
  try {
    a = std::stod(sine.substr(0, comma));
    l = comma == std::string::npos ? 0 : std::stod(sine.substr(comma + 1));
  } catch (const std::exception&) {  // std::stod's own errors: not a number
    comma = std::string::npos;
  }
  if (comma == std::string::npos)
    throw InputError(kCommandLine, 0, "--sine",
                     "expected AMPLITUDE_M,WAVELENGTH_M, got '" + sine + "'");
  if (!(a > 0) || !(l > 0))
    throw InputError(kCommandLine, 0, "--sine", "amplitude and wavelength must be > 0");
  return {a, l};
}

void PrintEnergy(const EnergyArgs& o, const nlohmann::json& j, const renderer::EnergyResult& r,
                 const renderer::EnergyPath& path) {
  fmt::print("algorithm {} on path {}: energy {:.6e} J", o.algorithm, j["path"].get<std::string>(),
             r.energy_J);
  if (r.has_closed_form && path.kind == renderer::EnergyPath::Kind::kA)
    fmt::print(" (eq. 5.2: {:.6e} J, difference {:.3f} %)", r.closed_form_J,
               100 * (r.energy_J - r.closed_form_J) / r.closed_form_J);
  fmt::print("\n");
  if (path.kind == renderer::EnergyPath::Kind::kB)
    fmt::print(
        "normal part {:.3e} J (closed form {:.3e} J), tangential part {:.3e} J;\n"
        "eq. (5.3) scale K mu^2 dx dz = {:.3e} J; gain bound = {:.3e} J\n",
        r.normal_energy_J, r.closed_form_J, r.tangential_energy_J, r.bound_J, r.gain_bound_J);
}

int RunEnergy(const EnergyArgs& o) {
  const auto [a, l] = ParseSine(o.sine);
  renderer::MaterialModel m;
  if (!o.model.empty()) {
    m = renderer::LoadMaterial(o.model);
  } else {
    m.contact.texture = {o.stiffness, 0, 1};
    m.contact.base = {2 * o.stiffness, 0, 1};
    m.contact.layer_thickness_m = 1e-3;
    m.friction = {2000, o.mu, 0};
  }
  const auto alg = renderer::ParseForceAlgorithm(o.algorithm);
  renderer::EnergyPath path;
  path.kind = alg == ForceAlgorithm::kNorm ? renderer::EnergyPath::Kind::kA
                                           : renderer::EnergyPath::Kind::kB;
  path.dx_max_m = o.dx;
  path.dz_max_m = o.dz > 0 ? o.dz : a;
  path.steps = o.steps;
  const auto r = renderer::ComputeEnergy(m, alg, a, l, path);
  nlohmann::json j = {{"algorithm", o.algorithm},
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
  if (o.json)
    PrintJson(j);
  else
    PrintEnergy(o, j, r, path);
  return kExitOk;
}

void AddEnergy(CLI::App& model) {
  auto o = std::make_shared<EnergyArgs>();
  auto* cmd = model.add_subcommand(
      "energy",
      "Work done by the rendered force field around a closed path on h = A sin(2 pi x / l)\n"
      "(dissertation Fig. 5.3). norm uses path A: (0,0)->(l/4,0)->(l/4,A)->(0,A)->(0,0), z from\n"
      "the mean surface, and is compared with eq. (5.2). fric1/fric2/wall use path B: down\n"
      "dz_max, along dx_max, up, back; the bound of eq. (5.3) is reported. Without --model,\n"
      "a linear texture layer (K = --stiffness, no damping) with friction --mu is used.\n"
      "Positive energy is created by the surface (non-passive).");
  cmd->add_option("--algorithm", o->algorithm, "Force algorithm")
      ->check(CLI::IsMember({"wall", "norm", "fric1", "fric2", "none"}))
      ->capture_default_str();
  cmd->add_option("--sine", o->sine, "AMPLITUDE_M,WAVELENGTH_M of the test texture")->required();
  cmd->add_option("--model", o->model, "Take contact and friction parameters from this model");
  cmd->add_option("--stiffness", o->stiffness, "Texture stiffness K without --model [N/m]")
      ->capture_default_str();
  cmd->add_option("--mu", o->mu, "Coulomb coefficient without --model")->capture_default_str();
  cmd->add_option("--dx-max", o->dx, "Path B tangential excursion [m]")->capture_default_str();
  cmd->add_option("--dz-max", o->dz, "Path B penetration [m] (default: the amplitude)");
  cmd->add_option("--steps", o->steps, "Integration steps per side")->capture_default_str();
  cmd->add_flag("--json", o->json, "Print {\"energy_J\", \"closed_form_J\", ...} as JSON");
  cmd->callback([o] { RunGuarded([&] { return RunEnergy(*o); }); });
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
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->callback([o] {
    RunGuarded([&] {
      auto r = renderer::ImportPennXml(o->xml);
      r.model.hybrid_cutoff_hz = o->cutoff;
      r.model.effects = {std::string(modeling::wb::effect::kCoulomb),
                         std::string(modeling::wb::effect::kVibrationSpeed),
                         std::string(modeling::wb::effect::kVibrationForce)};
      WriteTextFile(o->out, "# Imported from " + o->xml +
                                " (Penn Haptic Texture Toolkit format).\n" +
                                renderer::MaterialToToml(r.model));
      const auto& b = r.model.vibration;
      fmt::print(
          "{}: {} models ({}), order {}, mu {:.4f}; LSF reconstruction error {:.2e}; {} -> {}\n",
          o->xml, b.cells.size(), r.arma ? "ARMA" : "AR", b.order(), r.model.friction.mu_k,
          r.max_lsf_reconstruction_error,
          r.has_range
              ? fmt::format("range {:g} mm/s x {:g} N", b.max_speed_mps * 1e3, b.max_force_N)
              : std::string("no maxSpeed/maxForce: no saturation"),
          o->out);
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
      "build",
      "Assemble a complete material model from a height map (its .f32.toml from `model "
      "photometric`),\n"
      "a contact fit (`model fit-contact`) and a vibration bank (`model fit-vibration`). Every\n"
      "fitted effect and parameter of the parts is kept (the contact fit's effects, e.g.\n"
      "hc-exponent, and the bank's vibration-speed/vibration-force); the bank is written inline.");
  cmd->add_option("--name", o->name, "Material name")->required();
  cmd->add_option("--height", o->height,
                  "Geometry TOML written beside the height map (HEIGHT.f32.toml)")
      ->required();
  cmd->add_option("--contact", o->contact,
                  "Contact fit from fit-contact (a material TOML, or [contact] and [friction])")
      ->required();
  cmd->add_option("--vibration", o->vibration, "BANK.toml from fit-vibration")->required();
  cmd->add_option("--cutoff-hz", o->cutoff, "Hybrid filter cut-off f_c [Hz] (see `model cutoff`)")
      ->capture_default_str();
  cmd->add_option("-o,--out", o->out, "Material model to write (.toml)")->required();
  cmd->callback([o] {
    RunGuarded([&] {
      namespace fs = std::filesystem;
      const auto outdir = fs::absolute(o->out).parent_path();
      auto rel = [&](const std::string& p) {
        return fs::relative(fs::absolute(p), outdir).string();
      };
      auto quoted = [](const std::string& p) { return JsonText(nlohmann::json(p)); };
      // Each part is read through the renderer's material parser (its own file named in errors).
      // Parts without the tables a material requires get neutral ones (not used).
      auto parse = [](std::string text, const std::string& path, bool contact_part) {
        static const std::regex kName(R"((^|\n)[ \t]*name[ \t]*=)");
        if (!contact_part)
          text = "[contact]\ntexture_K = 1.0\n\n[friction]\nkappa_N_per_m = 1.0\nmu_k = 0.0\n\n" +
                 text;
        if (!std::regex_search(text, kName)) text = "name = \"part\"\n" + text;
        return renderer::ParseMaterial(text, path);
      };
      renderer::MaterialModel mm = parse(ReadTextFile(o->contact, "contact fit"), o->contact, true);
      const auto g = parse(ReadTextFile(o->height, "geometry table"), o->height, false);
      const auto v =
          parse("[vibration]\nfile = " + quoted(fs::absolute(o->vibration).string()) + "\n",
                o->vibration, false);
      mm.name = o->name;
      mm.source_path.clear();
      mm.geometry = g.geometry;
      mm.vibration = v.vibration;
      mm.hybrid_cutoff_hz = o->cutoff;
      if (mm.effects.empty()) {
        // A contact part without an effect list: the effects its parameters say were fitted.
        mm.effects = modeling::wb::ContactEffectsOf(mm);
      }
      if (!mm.vibration.empty())
        for (const auto e :
             {modeling::wb::effect::kVibrationSpeed, modeling::wb::effect::kVibrationForce})
          if (std::find(mm.effects.begin(), mm.effects.end(), e) == mm.effects.end())
            mm.effects.emplace_back(e);
      // The geometry by reference to its .f32, relative to the model.
      const auto f32 =
          (fs::absolute(o->height).parent_path() / fs::path(o->height).stem()).string();
      WriteTextFile(o->out, renderer::MaterialToToml(mm, rel(f32)));
      const auto m = renderer::LoadMaterial(o->out);  // validates the assembled model
      fmt::print("{}: {} ({}x{} map, {} vibration cells, f_c {:.0f} Hz; effects: {})\n", o->out,
                 m.name, m.geometry->width(), m.geometry->height(), m.vibration.cells.size(),
                 m.hybrid_cutoff_hz, fmt::join(m.effects, ", "));
      return kExitOk;
    });
  });
}
}  // namespace

void RegisterModel(CLI::App& app) {
  auto* model = app.add_subcommand(
      "model",
      "Material models: check, render offline, stability energy, import Penn XML,\n"
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
  AddScore(*model);
  AddIdentify(*model);
  AddFitContact(*model);
  AddPhotometric(*model);
  AddBuild(*model);
}

}  // namespace hapticlab::cli
