// Scoring a vibration model on a recording (vibration_score.hpp).
#include "hapticlab/modeling/vibration_score.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "hapticlab/modeling/neural.hpp"
#include "hapticlab/modeling/vibration.hpp"
#include "hapticlab/renderer/vibration.hpp"

namespace hapticlab::modeling {
namespace {

double Rms(const std::vector<double>& x) {
  double s = 0;
  for (const double v : x) s += v * v;
  return x.empty() ? 0 : std::sqrt(s / static_cast<double>(x.size()));
}

std::vector<double> SynthesizeBank(const renderer::VibrationBank& bank, double v, double f,
                                   std::size_t n, std::uint64_t seed) {
  renderer::VibrationInterpolator interp(bank);
  renderer::ArFilter filter;
  interp.Interpolate(v, f, true, &filter);
  filter.active = true;  // synthesize even below the renderer's switch-off speed
  renderer::ArSynth synth(seed);
  for (int k = 0; k < 4000; ++k) synth.Step(filter);  // let the filter settle
  std::vector<double> out(n);
  for (auto& x : out) x = synth.Step(filter);
  return out;
}

}  // namespace

renderer::MaterialModel LoadVibrationModel(const std::string& path) {
  const toml::table doc = ParseTomlFile(path, "model");
  renderer::MaterialModel m;
  if (doc.contains("name")) {
    m = renderer::LoadMaterial(path);
  } else if (doc.contains("topology")) {
    m.name = std::filesystem::path(path).stem().string();
    m.neural = std::make_shared<renderer::NeuralModel>(renderer::LoadNeuralModel(path));
  } else if (doc.contains("vibration")) {
    // A bank file alone: wrapped in a minimal material (placeholder contact) so that the
    // renderer's own reader parses and validates it exactly as inside a material model.
    const std::string abs = std::filesystem::absolute(path).string();
    m = renderer::ParseMaterial(
        fmt::format("name = \"{}\"\n[contact]\ntexture_K = 1.0\n[friction]\nkappa_N_per_m = "
                    "1.0\nmu_k = 0.0\n[vibration]\nfile = '{}'\n",
                    std::filesystem::path(path).stem().string(), abs),
        path);
  } else {
    throw InputError(path, 0, "",
                     "neither a material model (name = ...), a vibration bank ([vibration]) nor "
                     "a neural model (topology = ...)");
  }
  if (!m.neural && m.vibration.cells.empty())
    throw InputError(path, 0, "vibration", "the model has no vibration (no AR bank, no neural)");
  return m;
}

VibrationScore ScoreVibration(const renderer::MaterialModel& m, const Recording& r,
                              const ScoreOptions& o) {
  VibrationScore s;
  const auto& bank = m.vibration;
  if (m.neural) {
    s.kind = m.neural->topology == renderer::NeuralTopology::kUnified ? "neural unified"
                                                                      : "neural decomposed";
    s.model_rate_hz = m.neural->sample_rate_hz;
    s.model_calibrated = m.neural->calibrated;
  } else {
    s.kind = bank.cells.front().ma.empty() ? "ar bank" : "arma bank";
    s.model_rate_hz = bank.sample_rate_hz;
  }
  s.speed_mps = r.speed_mps;
  s.force_N = r.force_N;
  if (!r.labelled) {
    if (m.neural || bank.cells.size() != 1)
      throw InputError(r.file, 0, "speed_mps",
                       "the recording has no condition and the model more than one: give "
                       "--speed and --force (or a sidecar / metadata)");
    s.speed_mps = bank.cells.front().speed_mps;
    s.force_N = bank.cells.front().force_N;
    s.condition_from_model = true;
  }
  VibrationFitOptions pre;
  pre.model_rate_hz = s.model_rate_hz;
  pre.band_lo_hz = o.band_lo_hz;
  const std::vector<double> measured = Preprocess(r, pre);
  if (measured.size() < 1024)
    throw InputError(r.file, 0, "",
                     fmt::format("too short to score: {} samples at the model's {} Hz (1024 "
                                 "needed)",
                                 measured.size(), s.model_rate_hz));
  std::vector<double> synth =
      m.neural ? SynthesizeNeural(*m.neural, s.speed_mps, s.force_N, measured.size(), o.seed)
               : SynthesizeBank(bank, s.speed_mps, s.force_N, measured.size(), o.seed);
  const double rm = Rms(measured), rs = Rms(synth);
  if (!(rm > 0)) throw InputError(r.file, 0, "acc", "the recording is silent in the model's band");
  s.level_ratio = rs / rm;
  if (o.level_normalised && rs > 0)
    for (auto& v : synth) v *= rm / rs;
  s.es = SpectralError(measured, synth);
  return s;
}

}  // namespace hapticlab::modeling
