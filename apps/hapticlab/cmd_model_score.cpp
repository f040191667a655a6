// hapticlab model score / identify: any vibration model on any recording (E_s, level ratio).

#include <fmt/core.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "cmd_model.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/modeling/vibration_score.hpp"
#include "sound_flags.hpp"

namespace hapticlab::cli {
namespace {

struct ScoreArgs {
  std::string recording;
  SoundFlags sound;
  bool json = false, level_normalised = false;
  std::uint64_t seed = 1;
};

void AddScoreOptions(CLI::App* cmd, ScoreArgs& a) {
  cmd->add_option("--recording", a.recording,
                  "Recording: measurement CSV v1 with acc_mps2 (kinematics optional), WAV or FLAC")
      ->required();
  AddSoundFlags(cmd, a.sound);
  cmd->add_flag("--level-normalised", a.level_normalised,
                "Scale the synthesis to the recording's RMS before E_s (uncalibrated data, or "
                "sessions recorded at different levels): E_s then compares spectral shape");
  cmd->add_option("--seed", a.seed, "Synthesis seed")->capture_default_str();
  cmd->add_flag("--json", a.json, "As JSON");
}

nlohmann::json ScoreJson(const std::string& model, const modeling::VibrationScore& s) {
  return {{"model", model},
          {"kind", s.kind},
          {"speed_mps", s.speed_mps},
          {"force_N", s.force_N},
          {"condition_from_model", s.condition_from_model},
          {"es", s.es},
          {"level_ratio", s.level_ratio},
          {"model_rate_hz", s.model_rate_hz},
          {"model_calibrated", s.model_calibrated}};
}

std::string CalibrationWords(const modeling::Recording& r, bool normalised) {
  if (r.calibrated || normalised) return "";
  return " (the recording is uncalibrated: the level ratio is in its units and E_s depends on "
         "it; --level-normalised compares shapes)";
}

// A model trained on uncalibrated recordings plays in their units.
std::string ModelCalibrationWords(const modeling::VibrationScore& s, bool normalised) {
  if (s.model_calibrated) return "";
  return normalised ? " (the model is uncalibrated)"
                    : " (the model is uncalibrated: its level is in its training recordings' "
                      "units; --level-normalised compares shapes)";
}

}  // namespace

void AddScore(CLI::App& model) {
  auto a = std::make_shared<ScoreArgs>();
  auto m = std::make_shared<std::string>();
  auto* cmd = model.add_subcommand(
      "score",
      "E_s (eq. 3.1) and level ratio of a vibration model on a recording: the model's synthesis\n"
      "at the recording's (speed, force) against the recording resampled to the model's rate\n"
      "and band-limited as fit-vibration does. Models: a material model (AR bank, imported Penn\n"
      "ARMA bank or neural model), a bank file from fit-vibration, or a neural model file.");
  cmd->add_option("--model", *m, "Material model, bank or neural model file (.toml)")->required();
  AddScoreOptions(cmd, *a);
  cmd->callback([a, m] {
    RunGuarded([&] {
      const auto mat = modeling::LoadVibrationModel(*m);
      const auto rec = modeling::LoadRecording(a->recording, Labels(a->sound));
      const auto s = modeling::ScoreVibration(mat, rec, {a->level_normalised, a->seed});
      if (a->json) {
        auto j = ScoreJson(*m, s);
        j["recording"] = a->recording;
        j["level_normalised"] = a->level_normalised;
        j["calibrated"] = rec.calibrated;
        PrintJson(j);
        return kExitOk;
      }
      fmt::print("{} ({}) on {} at {:.4g} m/s, {:.4g} N{}: E_s {:.3f}{}, level ratio {:.3f}{}{}\n",
                 *m, s.kind, a->recording, s.speed_mps, s.force_N,
                 s.condition_from_model ? " (the model's only cell)" : "", s.es,
                 a->level_normalised ? " (level-normalised)" : "", s.level_ratio,
                 CalibrationWords(rec, a->level_normalised),
                 ModelCalibrationWords(s, a->level_normalised));
      return kExitOk;
    });
  });
}

void AddIdentify(CLI::App& model) {
  auto a = std::make_shared<ScoreArgs>();
  auto dir = std::make_shared<std::string>();
  auto* cmd = model.add_subcommand(
      "identify",
      "Rank the vibration models in a folder by E_s on one recording (as `model score` each):\n"
      "the first is the texture the recording most resembles.");
  cmd->add_option("--models", *dir, "Folder of model files (*.toml: materials, banks, neural)")
      ->required();
  AddScoreOptions(cmd, *a);
  cmd->callback([a, dir] {
    RunGuarded([&] {
      namespace fs = std::filesystem;
      if (!fs::is_directory(*dir)) throw InputError(*dir, 0, "models", "not a folder");
      std::vector<std::string> files;
      for (const auto& e : fs::directory_iterator(*dir))
        if (e.path().extension() == ".toml") files.push_back(e.path().string());
      std::sort(files.begin(), files.end());
      if (files.empty()) throw InputError(*dir, 0, "models", "no .toml models in the folder");
      const auto rec = modeling::LoadRecording(a->recording, Labels(a->sound));
      std::vector<std::pair<std::string, modeling::VibrationScore>> ranked;
      for (const auto& f : files)
        ranked.emplace_back(f, modeling::ScoreVibration(modeling::LoadVibrationModel(f), rec,
                                                        {a->level_normalised, a->seed}));
      std::stable_sort(ranked.begin(), ranked.end(),
                       [](const auto& x, const auto& y) { return x.second.es < y.second.es; });
      if (a->json) {
        nlohmann::json rows = nlohmann::json::array();
        for (const auto& [f, s] : ranked) rows.push_back(ScoreJson(f, s));
        PrintJson({{"recording", a->recording},
                   {"level_normalised", a->level_normalised},
                   {"calibrated", rec.calibrated},
                   {"ranking", rows}});
        return kExitOk;
      }
      fmt::print("{:>4} {:>7} {:>7}  {}\n", "rank", "E_s", "level", "model");
      for (std::size_t i = 0; i < ranked.size(); ++i)
        fmt::print("{:>4} {:>7.3f} {:>7.3f}  {}{}\n", i + 1, ranked[i].second.es,
                   ranked[i].second.level_ratio, ranked[i].first,
                   ranked[i].second.model_calibrated ? "" : " (uncalibrated model)");
      fmt::print("{} most resembles {}{}\n", a->recording, ranked.front().first,
                 CalibrationWords(rec, a->level_normalised));
      return kExitOk;
    });
  });
}

}  // namespace hapticlab::cli
