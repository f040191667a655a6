// hapticlab fit | compare | diagnose | effects | measurement: the model-versus-measurement
// workbench (DESIGN.md §4, docs/workbench.md). This file: registration, shared helpers, `effects`
// and `measurement`; fit, compare and diagnose have a file each (cmd_workbench_*.cpp).

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>

#include "cli_common.hpp"
#include "commands.hpp"
#include "fit_summary_json.hpp"
#include "hapticlab/core/measurement.hpp"
#include "hapticlab/modeling/sound_recording.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/renderer/neural.hpp"
#include "hapticlab/stats/plot.hpp"
#include "sound_flags.hpp"
#include "workbench_cli.hpp"

namespace hapticlab::cli {
namespace workbench_cli {

using namespace modeling::wb;

nlohmann::json ErrorsJson(const Errors& e) {
  nlohmann::json j = {{"overall", e.overall}};
  for (const auto& [k, v] : e.Normalized()) j["channels"][ChannelName(k)] = v;
  j["rms"] = {{"normal_force_N", e.normal_force_rms_N},
              {"tangential_N", e.tangential_rms_N},
              {"friction_ratio", e.friction_ratio_rms}};
  if (e.vibration.present) j["rms"]["vibration_Es"] = e.vibration.normalized;
  return j;
}

std::string AttachVibration(const std::string& path, Model* model) {
  const std::string what = AttachVibrationModel(model, path);
  if (what.empty()) return "";
  const bool uncalibrated =
      model->vibration_model->neural && !model->vibration_model->neural->calibrated;
  return fmt::format(
      "vibration: {}'s vibration is {}, scored by E_s of its spectrum at each window's speed and "
      "force in the measurement's bands up to {:.0f} Hz{}",
      path, what, VibrationModelTopHz(*model->vibration_model),
      uncalibrated ? " (the model is uncalibrated: its level is in its training recordings' "
                     "units, so E_s mixes level and shape)"
                   : "");
}

nlohmann::json EsCellsJson(const std::vector<EsCell>& cells) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& c : cells)
    j.push_back({{"condition", c.label},
                 {"speed_lo_mps", c.speed_lo_mps},
                 {"speed_hi_mps", std::isfinite(c.speed_hi_mps) ? nlohmann::json(c.speed_hi_mps)
                                                                : nlohmann::json()},
                 {"force_lo_N", c.force_lo_N},
                 {"force_hi_N",
                  std::isfinite(c.force_hi_N) ? nlohmann::json(c.force_hi_N) : nlohmann::json()},
                 {"windows", c.n},
                 {"es", c.es}});
  return j;
}

void PrintEsCells(const std::string& title, const std::vector<EsCell>& cells) {
  if (cells.empty()) return;
  fmt::print("\n{}:\n", title);
  for (const auto& c : cells)
    fmt::print("  {:28s} windows {:5d}  E_s {:.4f}\n", c.label, c.n, c.es);
}

std::string ErrorsLine(const Errors& e) {
  std::string s = fmt::format("overall {:.4f}", e.overall);
  for (const auto& [k, v] : e.Normalized()) s += fmt::format(", {} {:.4f}", ChannelName(k), v);
  s += fmt::format(" (rms: normal {:.4f} N, tangential {:.4f} N, friction ratio {:.4f})",
                   e.normal_force_rms_N, e.tangential_rms_N, e.friction_ratio_rms);
  return s;
}

Replay Load(const std::string& measurement, const Model* model, Measurement* keep,
            ReplayOptions* options) {
  // Vibration-only recordings: a clear refusal, not a missing column.
  constexpr const char* kNeeds =
      "holds vibration only; fit, compare and diagnose replay positions, velocities and forces "
      "(measurement CSV v1 with x_m..fz_N). Its vibration can be checked with `measurement "
      "check`, `model cutoff`, `model fit-vibration` and `model cv-vibration`";
  if (modeling::IsSoundFile(measurement))
    throw InputError(measurement, 0, "x_m", std::string("a WAV/FLAC recording ") + kNeeds);
  auto m = ReadMeasurementCsv(measurement, {.allow_vibration_only = true});
  if (!m.has_kinematics)
    throw InputError(measurement, 0, "x_m",
                     std::string("the file (t_s, acc_mps2, no x_m, y_m, z_m) ") + kNeeds);
  ReplayOptions o;
  if (model && model->HasVibration()) o.band_edges_hz = model->band_edges_hz;
  if (model && model->vibration_model) o.max_band_hz = VibrationModelTopHz(*model->vibration_model);
  auto r = PrepareReplay(m, o);
  if (keep) *keep = std::move(m);
  if (options) *options = o;
  return r;
}

nlohmann::json FitReportJson(const FitReport& rep) {
  nlohmann::json fits = nlohmann::json::array(), est;
  for (const auto& c : rep.channels) {
    fits.push_back(FitSummaryJson(c.summary));
    for (const auto& p : c.params)
      est[p.effect][p.name] = {{"value", p.value},
                               {"sd", p.sd},
                               {"lo95", p.lo95},
                               {"hi95", p.hi95},
                               {"at_bound", p.at_bound}};
  }
  return {{"fits", fits}, {"estimates", est}, {"usable", rep.IsUsable()}};
}

}  // namespace workbench_cli

namespace {

using namespace modeling::wb;
using namespace workbench_cli;

// ---------------------------------------------------------------------------------------------
void AddEffectsList(CLI::App& app) {
  auto json = std::make_shared<bool>(false);
  auto* cmd = app.add_subcommand(
      "effects", "List the workbench's catalogue of physical effects with their parameters");
  cmd->add_flag("--json", *json, "As JSON");
  cmd->callback([json] {
    RunGuarded([&] {
      const Replay empty;
      nlohmann::json j = nlohmann::json::array();
      for (const auto& e : Catalogue()) {
        nlohmann::json ps = nlohmann::json::array();
        std::string line;
        for (const auto& p : e->Params(empty)) {
          ps.push_back({{"name", p.name}, {"unit", p.unit}, {"fitted", p.fitted}, {"doc", p.doc}});
          if (p.fitted) line += fmt::format("{}{} [{}]", line.empty() ? "" : ", ", p.name, p.unit);
        }
        if (e->VibrationColumns())
          line += fmt::format("{}{} coefficients per band", line.empty() ? "" : ", ",
                              e->VibrationColumns());
        j.push_back({{"name", e->name()},
                     {"channel", ChannelName(e->channel())},
                     {"params", ps},
                     {"requires", e->requires_effects()},
                     {"description", e->description()}});
        if (!*json)
          fmt::print("{} ({}{}): {}\n  parameters: {}\n\n", e->name(), ChannelName(e->channel()),
                     e->requires_effects().empty()
                         ? ""
                         : fmt::format(", needs {}", fmt::join(e->requires_effects(), ", ")),
                     e->description(), line);
      }
      if (*json)
        PrintJson(j);
      else
        fmt::print("baseline (the thesis's model): {}\n", fmt::join(BaselineEffects(), ", "));
      return kExitOk;
    });
  });
}

// ---------------------------------------------------------------------------------------------
struct MeasurementCheckArgs {
  std::string file;
  bool json = false;
  SoundFlags sound;
};

int RunMeasurementCheck(const MeasurementCheckArgs& o) {
  if (modeling::IsSoundFile(o.file)) return CheckVibrationOnly(o.file, Labels(o.sound), o.json);
  const auto m = ReadMeasurementCsv(o.file, {.allow_vibration_only = true});
  if (!m.has_kinematics) return CheckVibrationOnly(o.file, Labels(o.sound), o.json);
  const auto s = Summarize(m);
  if (o.json) {
    nlohmann::json ranges;
    for (const auto& [k, v] : s.ranges) ranges[k] = {v.first, v.second};
    PrintJson(nlohmann::json{{"file", o.file},
                             {"material", m.material},
                             {"samples", s.samples},
                             {"duration_s", s.duration_s},
                             {"rate_hz", s.rate_hz},
                             {"gaps", s.gaps},
                             {"max_gap_s", s.max_gap_s},
                             {"contact_samples", s.contact_samples},
                             {"has_acceleration", m.has_acceleration},
                             {"ranges", ranges},
                             {"warnings", s.warnings}});
    return kExitOk;
  }
  fmt::print(
      "{}: material '{}', {} samples, {:.3f} s at {:.1f} Hz, {} in contact, {} gap{} "
      "(longest {:.4g} s)\n",
      o.file, m.material, s.samples, s.duration_s, s.rate_hz, s.contact_samples, s.gaps,
      s.gaps == 1 ? "" : "s", s.max_gap_s);
  for (const auto& [k, v] : s.ranges)
    fmt::print("  {:9s} {:+.6g} .. {:+.6g}\n", k, v.first, v.second);
  for (const auto& w : s.warnings) fmt::print("warning: {}\n", w);
  return kExitOk;
}

void AddMeasurementCheck(CLI::App* grp) {
  auto o = std::make_shared<MeasurementCheckArgs>();
  auto* cmd = grp->add_subcommand(
      "check",
      "Read a measurement CSV v1 (errors name file, line and column) and summarize it:\n"
      "duration, rate, ranges per column, gaps, samples in contact, warnings. A WAV/FLAC\n"
      "file or a vibration-only CSV (t_s, acc_mps2) is summarized as a vibration recording:\n"
      "format, rate, axes, condition, calibration, level.");
  cmd->add_option("FILE", o->file, "Measurement CSV v1, WAV or FLAC")->required();
  cmd->add_flag("--json", o->json, "As JSON");
  AddSoundFlags(cmd, o->sound);
  cmd->callback([o] { RunGuarded([&] { return RunMeasurementCheck(*o); }); });
}

struct SimulateArgs {
  std::string out;
  std::vector<std::string> effects, add;
  double duration_s = 120, rate_hz = 2000;
  std::uint64_t seed = 1;
};

int RunMeasurementSimulate(const SimulateArgs& o) {
  TruthParams t;
  t.effects = o.effects.empty() ? BaselineEffects() : o.effects;
  for (const auto& e : o.add) t.effects.push_back(e);
  RequireKnownEffects(t.effects, "<command line>", "--effects/--add");
  t.duration_s = o.duration_s;
  t.rate_hz = o.rate_hz;
  t.seed = o.seed;
  auto sim = Simulate(t);
  sim.m.material = "simulated";
  WriteMeasurementCsv(o.out, sim.m);
  fmt::print("wrote {} ({} samples, truth: {}, seed {})\n", o.out, sim.m.rows.size(),
             fmt::join(t.effects, ", "), t.seed);
  return kExitOk;
}

void AddMeasurementSimulate(CLI::App* grp) {
  auto o = std::make_shared<SimulateArgs>();
  auto* cmd = grp->add_subcommand(
      "simulate",
      "Write a measurement of simulated human-like strokes (2-150 mm/s, 0.3-2.5 N, pauses, "
      "lift-offs)\n"
      "on a ground-truth sample with the given effects (default: the baseline's), with sensor\n"
      "noise. For learning the workbench and testing a pipeline; the seed is recorded in the "
      "file.");
  cmd->add_option("-o,--out", o->out, "Measurement CSV v1 to write")->required();
  cmd->add_option("--effects", o->effects, "The truth's effects (default: the baseline's)");
  cmd->add_option("--add", o->add, "Effects on top of the baseline's (repeatable)");
  cmd->add_option("--duration", o->duration_s, "Length [s]")
      ->capture_default_str()
      ->check(CLI::Range(5.0, 3600.0));
  cmd->add_option("--rate", o->rate_hz, "Sample rate [Hz]")
      ->capture_default_str()
      ->check(CLI::Range(1000.0, 20000.0));
  cmd->add_option("--seed", o->seed, "Seed of every random draw")->capture_default_str();
  cmd->callback([o] { RunGuarded([&] { return RunMeasurementSimulate(*o); }); });
}

void AddMeasurement(CLI::App& app) {
  auto* grp = app.add_subcommand("measurement", "Check or simulate measurement CSV v1 files");
  grp->require_subcommand(1);
  AddMeasurementCheck(grp);
  AddMeasurementSimulate(grp);
}

}  // namespace

void RegisterWorkbench(CLI::App& app) {
  AddFit(app);
  AddCompare(app);
  AddDiagnose(app);
  AddEffectsList(app);
  AddMeasurement(app);
}

}  // namespace hapticlab::cli
