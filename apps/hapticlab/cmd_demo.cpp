// hapticlab demo: the most complete end-to-end path that exists today. It builds a
// synthetic material, renders a scripted stroke with every force algorithm through the
// real-time engine (force and vibration threads), records the trajectories to a study
// database through the writer thread, and exports the record as CSV. The simulated study
// (participants, ratings, analysis) replaces this once the study runner exists (issue #4).

#include <fmt/core.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/version.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/export.hpp"
#include "hapticlab/db/trajectory_writer.hpp"
#include "hapticlab/devices/replay.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/runner/rt_engine.hpp"

namespace hapticlab::cli {
namespace {

// A sandpaper-like synthetic material: random bumps (smoothed noise) 30 µm high on a
// 512 x 512 map at 20 µm pitch, Dahl friction, and a 3 x 3 AR(8) bank whose resonance rises
// with speed and whose power rises with speed and load.
renderer::MaterialModel DemoMaterial(std::uint64_t seed) {
  renderer::MaterialModel m;
  m.name = "Synthetic sandpaper (demo)";
  m.effects = {"coulomb", "viscous", "dahl", "hc-damping"};
  m.contact.texture = {1200, 5, 1.2};
  m.contact.base = {0, 0, 1};  // half the device's maximum stiffness
  m.contact.layer_thickness_m = 0.3e-3;
  m.friction = {3000, 0.45, 0.3};
  const int n = 512;
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> g(0.f, 1.f);
  std::vector<float> raw(static_cast<std::size_t>(n * n)), h(raw.size());
  for (auto& x : raw) x = g(rng);
  // 5 x 5 box blur, wrapped, then scaled to a 30 µm range.
  float lo = 1e9f, hi = -1e9f;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      float s = 0;
      for (int di = -2; di <= 2; ++di)
        for (int dj = -2; dj <= 2; ++dj) s += raw[static_cast<std::size_t>(((i + di + n) % n) * n + (j + dj + n) % n)];
      h[static_cast<std::size_t>(i * n + j)] = s;
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
  for (auto& x : h) x = (x - lo) / (hi - lo) * 30e-6f;
  m.geometry = std::make_shared<renderer::HeightMap>(n, n, 20e-6, std::move(h));
  auto& b = m.vibration;
  b.sample_rate_hz = 2000;
  b.grid_speeds_mps = {0.04, 0.08, 0.12};
  b.grid_forces_N = {0.54, 1.18, 1.91};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      renderer::ArCell c;
      c.speed_mps = b.grid_speeds_mps[static_cast<std::size_t>(i)];
      c.force_N = b.grid_forces_N[static_cast<std::size_t>(j)];
      for (int k = 0; k < 8; ++k) c.lsf.push_back((k + 0.4 + 0.25 * i) * 3.0 / 9.0 - 0.02 * j);
      c.coeffs = renderer::LsfToAr(c.lsf);
      c.variance = 0.05 * (1 + 2 * i) * (1 + j);
      b.cells.push_back(c);
    }
  m.hybrid_cutoff_hz = 100;
  return m;
}

// A scripted stroke like a participant's: back and forth over 6 cm (peak 11-19 cm/s),
// pressing 0.2-1.2 mm into the base under the layer (about 0.4-1.9 N with the demo's
// stiffnesses and a 3000 N/m device), sampled at 4 kHz.
std::vector<devices::TrajectorySample> ScriptedStroke(double seconds, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const double f_stroke = 0.6 + 0.4 * u(rng), phase = 2 * std::numbers::pi * u(rng);
  std::vector<devices::TrajectorySample> s;
  const double rate = 4000;
  for (int k = 0; k <= static_cast<int>(seconds * rate); ++k) {
    devices::TrajectorySample x;
    const double t = k / rate;
    const double w = 2 * std::numbers::pi * f_stroke;
    x.t_s = t;
    x.p_m = {0.03 * std::sin(w * t + phase), 0.002 * std::sin(0.3 * w * t), -(0.7e-3 + 0.5e-3 * std::sin(0.5 * w * t))};
    x.v_mps = {0.03 * w * std::cos(w * t + phase), 0.002 * 0.3 * w * std::cos(0.3 * w * t), -0.5e-3 * 0.5 * w * std::cos(0.5 * w * t)};
    s.push_back(x);
  }
  return s;
}

std::string UtcStamp() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%dT%H%M%SZ", &tm);
  return buf;
}

}  // namespace

void RegisterDemo(CLI::App& app) {
  struct O {
    std::string out;
    double seconds = 1.0;
    std::uint64_t seed = 20190819;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand(
      "demo",
      "Run the most complete end-to-end path that exists: a synthetic material rendered with\n"
      "every force algorithm (wall, norm, fric1, fric2, none+vibration) through the real-time\n"
      "engine on a scripted stroke, recorded to a study database and exported as CSV.\n"
      "Nothing is overwritten: each run writes a new timestamped folder.");
  cmd->add_option("--out", o->out, "Parent folder of the run's output (default: demo-out)");
  cmd->add_option("--seconds", o->seconds, "Stroke length per method [s]")->capture_default_str()
      ->check(CLI::Range(0.1, 60.0));
  cmd->add_option("--seed", o->seed, "Seed of the material and the strokes")->capture_default_str();
  cmd->callback([o] {
    const int rc = Guard([&] {
      namespace fs = std::filesystem;
      const fs::path dir = fs::path(o->out.empty() ? "demo-out" : o->out) / UtcStamp();
      fs::create_directories(dir);
      const auto material = DemoMaterial(o->seed);
      material.geometry->SaveRawF32((dir / "demo_material.f32").string());
      const std::string model_toml = MaterialToToml(material, "demo_material.f32");
      {
        std::FILE* f = std::fopen((dir / "demo_material.toml").c_str(), "w");
        if (!f) throw std::runtime_error((dir / "demo_material.toml").string() + ": cannot write");
        std::fputs(model_toml.c_str(), f);
        std::fclose(f);
      }
      const std::string db_path = (dir / "demo.db").string();
      db::Database database(db_path);
      const std::string protocol =
          "# Renderer demo (no ratings): every force algorithm on one synthetic material.\n"
          "seed = " + std::to_string(o->seed) + "\nmethods = [\"wall\", \"norm\", \"fric1\", \"fric2\", \"none\"]\n";
      const auto study = database.CreateStudy({.name = "renderer-demo", .protocol_toml = protocol, .seed = o->seed});
      const auto participant = database.AddParticipant({.study_id = study, .code = "SIM01", .index = 0, .seed = o->seed});
      database.SaveMaterialModel(material.name, model_toml);
      const nlohmann::json provenance = {{"protocol_hash", db::HashText(protocol)},
                                         {"seed", o->seed},
                                         {"model_hash", db::HashText(model_toml)},
                                         {"device", "replay (scripted stroke)"}};
      const auto session = database.StartSession({.participant_id = participant,
                                                  .software_version = std::string(kVersion) + "+" + kGitSha,
                                                  .device = "replay",
                                                  .calibration = "none (simulated)",
                                                  .provenance_json = provenance.dump()});
      struct Method {
        const char* name;
        renderer::ForceAlgorithm alg;
        bool vibration;
      };
      const Method methods[] = {{"wall", renderer::ForceAlgorithm::kWall, false},
                                {"norm", renderer::ForceAlgorithm::kNorm, false},
                                {"fric1", renderer::ForceAlgorithm::kFric1, false},
                                {"fric2", renderer::ForceAlgorithm::kFric2, false},
                                {"none", renderer::ForceAlgorithm::kNone, true},
                                {"fric2+vibration", renderer::ForceAlgorithm::kFric2, true}};
      std::vector<db::Trial> plan;
      int idx = 0;
      for (const auto& m : methods)
        plan.push_back({.session_id = session, .plan_index = idx++, .phase = "main", .material = material.name,
                        .comparison = "virtual", .method = m.name, .left = "virtual", .right = ""});
      const auto trial_ids = database.AddTrials(plan);
      db::TrajectoryWriter writer(db_path);
      fmt::print("HapticLab {} ({}) renderer demo -> {}\n", kVersion, kGitSha, dir.string());
      fmt::print("{:<16} {:>9} {:>10} {:>10} {:>9} {:>9} {:>10} {:>7}\n", "method", "ticks", "mean Fn N",
                 "mean Ff N", "vib rms", "force Hz", "jitter us", "faults");
      idx = 0;
      for (const auto& m : methods) {
        const auto trial = trial_ids[static_cast<std::size_t>(idx)];
        database.StartTrial(trial);
        renderer::RenderOptions ro;
        ro.algorithm = m.alg;
        ro.vibration = m.vibration;
        ro.force_rate_hz = 1000;
        ro.vibration_rate_hz = 10000;
        ro.seed = o->seed + static_cast<std::uint64_t>(idx);
        renderer::HybridRenderer renderer(material, ro);
        runner::RtEngine* engine_ptr = nullptr;
        devices::ReplayDevice device(ScriptedStroke(o->seconds, o->seed + 100), [&] { return engine_ptr->Now(); });
        devices::BufferActuator actuator(ro.vibration_rate_hz,
                                         static_cast<std::size_t>(ro.vibration_rate_hz * (o->seconds + 1)));
        auto* fs_ = writer.OpenStream(trial, "force", ro.force_rate_hz, runner::ForceStreamChannels());
        auto* vs = writer.OpenStream(trial, "vibration", ro.vibration_rate_hz, runner::VibrationStreamChannels());
        runner::RtEngine engine(renderer, device, &actuator, {}, fs_, vs);
        engine_ptr = &engine;
        engine.RunFor(std::chrono::duration<double>(o->seconds + 0.5));
        writer.CloseStream(fs_);
        writer.CloseStream(vs);
        const auto st = engine.Stats();
        // Summaries from the record itself (what an analyst would see).
        double fn = 0, ff = 0;
        std::size_t n = 0;
        double v2 = 0;
        std::size_t nv = 0;
        for (const auto& c : database.TrajectoryChunks(trial)) {
          const std::size_t nc = c.channels.size();
          for (std::size_t i = 0; i < c.sample_count(); ++i) {
            if (c.stream == "force") {
              fn += c.samples[i * nc + 12];
              ff += std::hypot(c.samples[i * nc + 9], c.samples[i * nc + 10]);
              ++n;
            } else {
              v2 += c.samples[i] * c.samples[i];
              ++nv;
            }
          }
        }
        const auto faults = renderer.counters().nan_faults.load() + renderer.counters().stale_faults.load() + st.miss_faults;
        database.LogEvent({.session_id = session, .trial_id = trial, .kind = "render-stats",
                           .detail = nlohmann::json{{"force_ticks", st.force_ticks},
                                                    {"vibration_ticks", st.vibration_ticks},
                                                    {"force_rate_hz", st.achieved_force_rate_hz},
                                                    {"vibration_rate_hz", st.achieved_vibration_rate_hz},
                                                    {"force_jitter_max_s", st.force_jitter_max_s},
                                                    {"force_deadline_misses", st.force_deadline_misses},
                                                    {"vibration_deadline_misses", st.vibration_deadline_misses},
                                                    {"saturations", renderer.counters().saturations.load()},
                                                    {"faults", faults},
                                                    {"recording_overflows", st.recording_overflows}}
                                         .dump()});
        database.CompleteTrial(trial, {});  // a rendering trial: no ratings are collected yet
        fmt::print("{:<16} {:>9} {:>10.3f} {:>10.3f} {:>9.3f} {:>9.0f} {:>10.1f} {:>7}\n", m.name, st.force_ticks,
                   n ? fn / static_cast<double>(n) : 0.0, n ? ff / static_cast<double>(n) : 0.0,
                   nv ? std::sqrt(v2 / static_cast<double>(nv)) : 0.0, st.achieved_force_rate_hz,
                   st.force_jitter_max_s * 1e6, faults);
        ++idx;
      }
      database.EndSession(session, "completed");
      const auto files = db::ExportCsv(database, (dir / "export").string());
      fmt::print("\ndatabase: {}\nmaterial: {}\nexport:   {} ({} files)\n", db_path,
                 (dir / "demo_material.toml").string(), (dir / "export").string(), files.size());
      fmt::print("The simulated study with participants and ratings arrives with issue #4.\n");
      return kExitOk;
    });
    if (rc != kExitOk) throw CLI::RuntimeError(rc);
  });
}

}  // namespace hapticlab::cli
