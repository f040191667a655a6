// hapticlab model fit-vibration, fit-neural, cv-vibration, cutoff: vibration banks.

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
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
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/energy.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/renderer/penn_import.hpp"
#include "hapticlab/runner/offline.hpp"
#include "hapticlab/stats/plot.hpp"
#include "sound_flags.hpp"

namespace hapticlab::cli {
namespace {

std::vector<double> ParseList(const std::string& s, const char* opt) {
  std::vector<double> out;
  std::size_t a = 0;
  while (a <= s.size()) {
    const auto b = s.find(',', a);
    const std::string part = s.substr(a, b == std::string::npos ? std::string::npos : b - a);
    try {
      if (!part.empty()) out.push_back(std::stod(part));
    } catch (const std::exception&) {
      throw InputError(kCommandLine, 0, opt, "expected comma-separated numbers, got '" + s + "'");
    }
    if (b == std::string::npos) break;
    a = b + 1;
  }
  return out;
}

// The modeling library's names for what these commands' options give it.
const std::map<std::string, std::string> kVibFlags = {{"recordings", "--recordings"},
                                                      {"model_rate_hz", "--rate"}};

inline constexpr EnumTable<modeling::OrderCriterion, 2> kCriterionNames{
    {{modeling::OrderCriterion::kAic, "aic"}, {modeling::OrderCriterion::kBic, "bic"}}};

struct VibArgs {
  std::string recordings, out, order = "auto";
  modeling::OrderCriterion criterion = modeling::OrderCriterion::kAic;
  double rate = 2000, band_lo = 20;
  SoundFlags sound;
  int max_order = 30;
};

constexpr const char* kRecordingsHelp =
    "Folder of recordings, one or more per (speed, force) condition (pooled): measurement CSV "
    "v1 with acc_mps2 (kinematics optional), WAV or FLAC (docs/formats.md)";

void AddVibOptions(CLI::App* cmd, VibArgs& a) {
  cmd->add_option("--recordings", a.recordings, kRecordingsHelp)->required();
  AddSoundFlags(cmd, a.sound);
  cmd->add_option("--rate", a.rate, "Model sample rate [Hz] (2000 in the thesis)")
      ->capture_default_str();
  cmd->add_option("--order", a.order, "AR order: a number, or auto (information criterion)")
      ->capture_default_str();
  cmd->add_option("--max-order", a.max_order,
                  "Largest AR order the criterion may choose (--order auto); an order at this "
                  "cap is reported")
      ->check(CLI::Range(1, renderer::kMaxArOrder))
      ->capture_default_str();
  AddEnumOption(cmd, "--criterion", a.criterion, kCriterionNames, "Order criterion");
  cmd->add_option("--band-low", a.band_lo, "High-pass of the band limit [Hz]")
      ->capture_default_str();
}

modeling::VibrationFitOptions VibOptions(const VibArgs& a) {
  modeling::VibrationFitOptions o;
  o.model_rate_hz = a.rate;
  o.band_lo_hz = a.band_lo;
  o.max_order = a.max_order;
  o.criterion = a.criterion;
  if (a.order != "auto") {
    try {
      o.order = std::stoi(a.order);
    } catch (const std::exception&) {
      throw InputError(kCommandLine, 0, "--order",
                       "expected a number or auto, got '" + a.order + "'");
    }
    if (o.order < 1 || o.order > 64) throw InputError(kCommandLine, 0, "--order", "expected 1..64");
  }
  return o;
}

// The criterion chose the cap itself: it may want a larger order.
std::string AtCapNote(const VibArgs& a, int order) {
  return a.order == "auto" && order == a.max_order
             ? fmt::format(" (the --max-order cap: the {} may prefer more)",
                           NameOf(kCriterionNames, a.criterion))
             : std::string();
}

}  // namespace

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
    RunGuarded(kVibFlags, [&] {
      const auto recs = modeling::LoadRecordings(a->recordings, Labels(a->sound));
      const auto bank = modeling::FitVibrationBank(recs, VibOptions(*a));
      renderer::MaterialModel holder;
      holder.vibration = bank;
      std::string text = renderer::MaterialToToml(holder);
      text = text.substr(text.find("[vibration]"));  // the bank alone
      const bool calibrated = modeling::AllCalibrated(recs);
      WriteTextFile(a->out, "# AR bank fitted by hapticlab model fit-vibration from " +
                                a->recordings + "\n" +
                                (calibrated ? ""
                                            : "# uncalibrated: variances in the recordings' "
                                              "own units squared, not (m/s^2)^2\n") +
                                text);
      fmt::print("{} recordings -> {} cells ({}), order {}{} at {:.0f} Hz -> {}{}\n", recs.size(),
                 bank.cells.size(), bank.grid_speeds_mps.empty() ? "triangulated" : "grid",
                 bank.order(), AtCapNote(*a, bank.order()), bank.sample_rate_hz, a->out,
                 CalibrationNote(calibrated));
      return kExitOk;
    });
  });
}

// fit-neural --topology: the names the neural model file uses (renderer/neural_io.cpp).
inline constexpr EnumTable<renderer::NeuralTopology, 2> kTopologyNames{
    {{renderer::NeuralTopology::kUnified, "unified"},
     {renderer::NeuralTopology::kDecomposed, "decomposed"}}};

void AddFitNeural(CLI::App& model) {
  struct O {
    VibArgs a;
    renderer::NeuralTopology topology = renderer::NeuralTopology::kUnified;
    int epochs = 40;
    double input_noise = 0.3;
    std::uint64_t seed = 1;
    int threads = 0;
  };
  auto o = std::make_shared<O>();
  auto* cmd = model.add_subcommand(
      "fit-neural",
      "Train the neural texture model (dissertation ch. III.3, Fig. 3.3) from recordings on a "
      "full\n"
      "speed x force grid: four bands (20-100, 100-200, 200-500, 500-1000 Hz; decimation 8, 4,\n"
      "1, 1), an MLP per band with 50 inputs (Γ_U: one per band with v and f as inputs, hidden\n"
      "30-25-15-5; Γ_D: one per band and grid cell, 30-25-15-5 for band 1 and 30-15-5 for the\n"
      "others), Adam with mini-batches and early stopping. Writes a neural model file; reference\n"
      "it from a material with [neural] file = \"F\" (docs/modeling-neural.md).");
  cmd->add_option("--recordings", o->a.recordings, kRecordingsHelp)->required();
  AddSoundFlags(cmd, o->a.sound);
  AddEnumOption(cmd, "--topology", o->topology, kTopologyNames,
                "unified (Γ_U) or decomposed (Γ_D)");
  cmd->add_option("-o,--out", o->a.out, "Neural model file to write (.toml)")->required();
  cmd->add_option("--rate", o->a.rate, "Model sample rate [Hz]")->capture_default_str();
  cmd->add_option("--epochs", o->epochs, "Maximum training epochs per network")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000));
  cmd->add_option("--input-noise", o->input_noise,
                  "Noise on training histories (units of the band RMS)")
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Initialisation, shuffling and noise seed")
      ->capture_default_str();
  cmd->add_option("--threads", o->threads, "Networks trained in parallel (0: all cores)")
      ->capture_default_str();
  cmd->callback([o] {
    RunGuarded(kVibFlags, [&] {
      const auto loaded = modeling::LoadRecordings(o->a.recordings, Labels(o->a.sound));
      modeling::RequireConditions(loaded, "fit-neural");
      const auto recs = modeling::PoolByCondition(loaded);  // one per grid cell
      modeling::NeuralFitOptions no;
      no.topology = o->topology;
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
      fmt::print("{} recordings ({} speeds x {} forces) -> {} model, {} bands -> {}{}\n",
                 loaded.size(), m.speeds_mps.size(), m.forces_N.size(),
                 NameOf(kTopologyNames, o->topology), m.bands.size(), o->a.out,
                 CalibrationNote(modeling::AllCalibrated(recs)));
      return kExitOk;
    });
  });
}

namespace {

// cv-vibration --model-kind: the AR bank or a neural topology.
enum class VibModelKind { kLpc, kNeuralUnified, kNeuralDecomposed };
inline constexpr EnumTable<VibModelKind, 3> kVibModelKindNames{
    {{VibModelKind::kLpc, "lpc"},
     {VibModelKind::kNeuralUnified, "neural-unified"},
     {VibModelKind::kNeuralDecomposed, "neural-decomposed"}}};

struct CvArgs {
  VibArgs a;
  std::string train_speeds = "0.04,0.08,0.12";
  std::string train_forces = "0.54,1.18,1.91";
  bool json = false;
  std::uint64_t seed = 1;
  std::string plots;
  VibModelKind kind = VibModelKind::kLpc;
  int epochs = 40;
};

// Measured vs synthesized spectra per condition (Figs. 3.5/3.6), SVG and PNG in o.plots.
void DrawCvSpectra(const CvArgs& o, const modeling::CvResult& cv) {
  std::filesystem::create_directories(o.plots);
  for (const auto& r : cv.rows) {
    stats::LinePlot lp;
    lp.title = fmt::format("{:.0f} mm/s, {:.2f} N ({}), E_s = {:.3f}", r.speed_mps * 1e3, r.force_N,
                           r.train ? "training" : "held out", r.es);
    lp.x_label = "frequency [Hz]";
    lp.y_label = "|A(f)|";
    lp.log_y = true;
    for (std::size_t k = 0; k < r.measured_spectrum.size(); ++k)
      lp.x.push_back(static_cast<double>(k) * VibOptions(o.a).model_rate_hz /
                     (2.0 * static_cast<double>(r.measured_spectrum.size() - 1)));
    lp.series = {{"measured", r.measured_spectrum}, {"synthesized", r.synthesized_spectrum}};
    stats::DrawLinePlot(
        lp, (std::filesystem::path(o.plots) /
             fmt::format("spectrum_v{:.0f}_f{:.0f}", r.speed_mps * 1e3, r.force_N * 100))
                .string());
  }
}

// The E_s table: one row per recording, then the means (or the same as JSON).
void PrintCv(const CvArgs& o, const std::vector<modeling::Recording>& recs,
             const modeling::CvResult& cv, bool calibrated) {
  if (o.json) {
    nlohmann::json rows = nlohmann::json::array();
    for (std::size_t i = 0; i < cv.rows.size(); ++i) {
      const auto& r = cv.rows[i];
      rows.push_back({{"file", recs[i].file},
                      {"speed_mps", r.speed_mps},
                      {"force_N", r.force_N},
                      {"split", r.train ? "train" : "test"},
                      {"es", r.es}});
    }
    PrintJson(nlohmann::json{{"model_kind", std::string(NameOf(kVibModelKindNames, o.kind))},
                             {"calibrated", calibrated},
                             {"conditions", rows},
                             {"mean_es_train", cv.mean_es_train},
                             {"mean_es_test", cv.mean_es_test},
                             {"order", cv.order}});
    return;
  }
  fmt::print("{:>10} {:>9} {:>6} {:>7}  {}\n", "speed m/s", "force N", "split", "E_s", "file");
  for (std::size_t i = 0; i < cv.rows.size(); ++i) {
    const auto& r = cv.rows[i];
    fmt::print("{:>10.3f} {:>9.3f} {:>6} {:>7.3f}  {}\n", r.speed_mps, r.force_N,
               r.train ? "train" : "test", r.es, recs[i].file);
  }
  const bool any_test =
      std::any_of(cv.rows.begin(), cv.rows.end(), [](const auto& r) { return !r.train; });
  fmt::print("mean E_s ({}): training {:.3f}, held-out {}{}{}\n",
             NameOf(kVibModelKindNames, o.kind), cv.mean_es_train,
             any_test ? fmt::format("{:.3f}", cv.mean_es_test)
                      : std::string("n/a (no held-out conditions)"),
             o.kind == VibModelKind::kLpc
                 ? fmt::format(" (AR order {}{})", cv.order, AtCapNote(o.a, cv.order))
                 : std::string(),
             CalibrationNote(calibrated));
}

int RunCvVibration(const CvArgs& o) {
  const auto recs = modeling::LoadRecordings(o.a.recordings, Labels(o.a.sound));
  const bool calibrated = modeling::AllCalibrated(recs);
  modeling::CvResult cv;
  if (o.kind == VibModelKind::kLpc) {
    cv = modeling::CrossValidate(recs, ParseList(o.train_speeds, "--train-speeds"),
                                 ParseList(o.train_forces, "--train-forces"), VibOptions(o.a),
                                 o.seed);
  } else {
    modeling::NeuralFitOptions no;
    no.topology = o.kind == VibModelKind::kNeuralUnified ? renderer::NeuralTopology::kUnified
                                                         : renderer::NeuralTopology::kDecomposed;
    no.preprocess = VibOptions(o.a);
    no.train.max_epochs = o.epochs;
    no.train.seed = o.seed;
    cv = modeling::CrossValidateNeural(recs, ParseList(o.train_speeds, "--train-speeds"),
                                       ParseList(o.train_forces, "--train-forces"), no, o.seed);
  }
  if (!o.plots.empty()) DrawCvSpectra(o, cv);
  PrintCv(o, recs, cv, calibrated);
  return kExitOk;
}

}  // namespace

void AddCvVibration(CLI::App& model) {
  auto o = std::make_shared<CvArgs>();
  auto* cmd = model.add_subcommand(
      "cv-vibration",
      "Cross-validation as dissertation ch. III.4: fit on the training speeds x forces, then\n"
      "E_s (eq. 3.1) of the renderer's interpolated synthesis at every recorded condition;\n"
      "--plots draws measured vs synthesized spectra like Figs. 3.5/3.6.");
  AddVibOptions(cmd, o->a);
  cmd->add_option("--train-speeds", o->train_speeds, "Training speeds [m/s], comma-separated")
      ->capture_default_str();
  cmd->add_option("--train-forces", o->train_forces, "Training forces [N], comma-separated")
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Synthesis seed")->capture_default_str();
  cmd->add_option("--plots", o->plots,
                  "Write measured vs synthesized spectra per condition here (SVG and PNG)");
  cmd->add_flag("--json", o->json,
                "Print {\"conditions\":[...],\"mean_es_train\",\"mean_es_test\"}");
  AddEnumOption(
      cmd, "--model-kind", o->kind, kVibModelKindNames,
      "lpc: the AR bank; neural-unified: Γ_U; neural-decomposed: Γ_D (dissertation ch. III.3, "
      "Fig. 3.7: run all three on the same recordings for one E_s table)");
  cmd->add_option("--epochs", o->epochs, "Neural models: maximum training epochs")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000));
  cmd->callback([o] { RunGuarded(kVibFlags, [&] { return RunCvVibration(*o); }); });
}

void AddCutoff(CLI::App& model) {
  auto file = std::make_shared<std::string>();
  auto lo = std::make_shared<double>(50), hi = std::make_shared<double>(150),
       step = std::make_shared<double>(10);
  auto json_out = std::make_shared<bool>(false);
  auto max_s = std::make_shared<double>(0);
  auto* cmd = model.add_subcommand(
      "cutoff",
      "Stationarity cut-off (dissertation ch. III.5): the smallest high-pass cut-off in the range\n"
      "whose filtered recording rejects a unit root (augmented Dickey-Fuller, 5 %, on the whole\n"
      "recording unless --max-seconds). It becomes the material's hybrid filter f_c. When the\n"
      "lowest cut-off tried already passes, it says \"stationary at every tested cut-off\" with\n"
      "the statistic: the range, not the recording, set the value (try a lower --from).");
  auto sound = std::make_shared<SoundFlags>();
  cmd->add_option("--recording", *file,
                  "Measurement CSV v1 with acc_mps2 (kinematics optional), WAV or FLAC")
      ->required();
  AddSoundFlags(cmd, *sound);
  cmd->add_option("--from", *lo, "Lowest cut-off [Hz]")->capture_default_str();
  cmd->add_option("--to", *hi, "Highest cut-off [Hz]")->capture_default_str();
  cmd->add_option("--step", *step, "Step [Hz]")->capture_default_str();
  cmd->add_option("--max-seconds", *max_s,
                  "Test only the first this many seconds (0: the whole recording)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--json", *json_out, "Print the result and every cut-off tried as JSON");
  cmd->callback([=] {
    RunGuarded([&] {
      const auto r = modeling::LoadRecording(*file, Labels(*sound));
      const auto c =
          modeling::StationarityCutoff(r.acc, r.rate_hz, *lo, *hi, *step,
                                       static_cast<std::size_t>(std::llround(*max_s * r.rate_hz)));
      if (*json_out) {
        nlohmann::json tried = nlohmann::json::array();
        for (const auto& [fc, adf] : c.tried)
          tried.push_back({{"cutoff_hz", fc},
                           {"adf", adf.statistic},
                           {"critical_5pct", adf.critical_5pct},
                           {"lags", adf.lags},
                           {"stationary", adf.rejects_unit_root}});
        PrintJson(
            nlohmann::json{{"found", c.found},
                           {"cutoff_hz", c.found ? nlohmann::json(c.cutoff_hz) : nlohmann::json()},
                           {"stationary_at_every_cutoff", c.stationary_at_every_cutoff},
                           {"samples", c.samples},
                           {"seconds", static_cast<double>(c.samples) / r.rate_hz},
                           {"tried", tried}});
      } else if (c.stationary_at_every_cutoff) {
        const auto& adf = c.tried.front().second;
        fmt::print(
            "stationary at every tested cut-off: already at the lowest, {:.1f} Hz (ADF {:.2f} < "
            "{:.2f} at 5 %, {} lags, {:.1f} s); f_c is at most {:.1f} Hz, try a lower --from\n",
            c.cutoff_hz, adf.statistic, adf.critical_5pct, adf.lags,
            static_cast<double>(c.samples) / r.rate_hz, c.cutoff_hz);
      } else if (c.found) {
        fmt::print("f_c = {:.1f} Hz (ADF {:.2f} < {:.2f} at 5 %)\n", c.cutoff_hz,
                   c.tried.back().second.statistic, c.tried.back().second.critical_5pct);
      } else {
        fmt::print("no cut-off in {:.0f}-{:.0f} Hz makes the recording stationary\n", *lo, *hi);
      }
      return c.found ? kExitOk : kExitFailure;
    });
  });
}

}  // namespace hapticlab::cli
