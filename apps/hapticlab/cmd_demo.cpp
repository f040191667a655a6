// hapticlab demo: the main job. A complete simulated study end to end: the dissertation's
// chapter V.3 hybrid-realism protocol run by simulated participants in the simulated lab,
// recorded to a new SQLite database, then analysed into a report. Every trial runs through
// the real-time engine on a virtual clock (the simulated rig); a last check runs the engine
// on the real clock (force and vibration threads).

#include <fmt/core.h>

#include <chrono>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/version.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/export.hpp"
#include "hapticlab/design/power_pool.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/rt_engine.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/sim/sim_device.hpp"
#include "hapticlab/sim/sim_lab.hpp"
#include "hapticlab/stats/power.hpp"
#include "hapticlab/stats/report.hpp"

#ifndef HL_SOURCE_DIR
#define HL_SOURCE_DIR "."
#endif

namespace hapticlab::cli {
namespace {

namespace fs = std::filesystem;

std::string UtcStamp() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%dT%H%M%SZ", &tm);
  return buf;
}

// One second of the Hybrid method on a placeholder model through the real-time engine on
// the real clock: a 1 kHz force thread and a 10 kHz vibration thread driving the generic
// simulated device, whose simulated hand strokes the virtual sample.
// Returns the methods-section sentence for the demo's report: the simulated participants ran
// on a virtual clock, so the report's timing figures are this check's, on this computer.
std::string RealTimeCheck(const std::string& profiles_path) {
  const auto set = sim::LoadProfiles(profiles_path);
  const auto model = sim::PlaceholderModel(set.profiles.at("Denim"));
  renderer::RenderOptions ro;
  ro.algorithm = renderer::ForceAlgorithm::kFric2;
  renderer::HybridRenderer r(model, ro);
  Rng rng(1);
  sim::Hand hand;
  sim::SimDevice dev(sim::SimDeviceModel{}, hand, nullptr);  // null clock: the real one
  sim::SimActuator act(hand, ro.vibration_rate_hz);
  hand.Begin(sim::DrawStroke(rng), Eigen::Isometry3d::Identity(),
             model.contact.layer_thickness_m + model.geometry->max_m() - model.geometry->min_m(),
             model.contact.texture.K + 0.5 * ro.device_max_stiffness_N_per_m, nullptr,
             ro.force_rate_hz, ro.vibration_rate_hz);
  runner::RtEngine engine(r, dev, &act);
  engine.RunFor(std::chrono::seconds(1));
  const auto st = engine.Stats();
  const auto& ft = st.force_timing;
  fmt::print(
      "real-time engine check (Denim, Hybrid, 1 s on the real clock): force loop {:.0f} Hz, "
      "vibration loop {:.0f} Hz, "
      "force wake-up lateness p50 {:.1f} us, p99 {:.1f} us, p99.9 {:.1f} us, max {:.1f} us (timer "
      "slack {} ns, {}), "
      "deadline misses {}/{}, in contact {} of {} ticks, faults {}\n",
      st.achieved_force_rate_hz, st.achieved_vibration_rate_hz, ft.late_p50_s * 1e6,
      ft.late_p99_s * 1e6, ft.late_p999_s * 1e6, ft.late_max_s * 1e6,
      st.force_thread.timer_slack_ns, st.force_thread.priority_status, st.force_deadline_misses,
      st.vibration_deadline_misses, st.contact_ticks, st.force_ticks,
      r.counters().nan_faults.load() + r.counters().stale_faults.load());
  const auto& vt = st.vibration_timing;
  return fmt::format(
      "Real-time check on the computer that ran this demo ({}; the simulated participants above "
      "ran on a "
      "virtual clock, so these are the engine's figures on this computer, not the sessions'): the "
      "Hybrid method "
      "(Denim) ran 1 s on the real clock with a simulated hand stroking the virtual sample; the "
      "force loop "
      "(requested {:.0f} Hz) achieved {:.1f} Hz with wake-up lateness p50 {:.1f} us, p99 {:.1f} "
      "us, p99.9 {:.1f} us "
      "(max {:.1f} us) and {} deadline misses; the vibration loop (requested {:.0f} Hz) achieved "
      "{:.1f} Hz with "
      "lateness p50 {:.1f} us, p99 {:.1f} us; timer slack {} ns, {}, spin {} us before each force "
      "deadline.\n",
      UtcStamp(), ro.force_rate_hz, st.achieved_force_rate_hz, ft.late_p50_s * 1e6,
      ft.late_p99_s * 1e6, ft.late_p999_s * 1e6, ft.late_max_s * 1e6, st.force_deadline_misses,
      ro.vibration_rate_hz, st.achieved_vibration_rate_hz, vt.late_p50_s * 1e6, vt.late_p99_s * 1e6,
      st.force_thread.timer_slack_ns, st.force_thread.priority_status,
      runner::EngineOptions{}.rt.spin_us);
}

// One line of `study power`: participants for 80 % power on the method effect, from the
// demo's own participants' interactions re-rated by fresh simulated observers of the
// protocol's observer model (the calibrated studies/shin2019/observer.toml for the default
// protocol; the built-in uncalibrated one for a protocol that names none), named in the line.
void PowerLine(const protocols::Protocol& p, const design::FeltPool& pool) {
  bool has_main = false;
  for (const auto& v : pool.participants)
    for (const auto& t : v) has_main |= t.phase == PhaseKind::kMain;
  if (!has_main || p.methods.size() < 2) return;
  const auto model = design::ChooseObserver(p, p.observer.empty() ? "builtin" : "");
  stats::PowerOptions po;
  // A quick estimate (a few seconds): 40 studies per count; `study power` for more.
  po.participants = {4, 6, 8, 12, 16, 24};
  po.simulations = 40;
  po.seed = p.seed;
  po.effects = {"method"};
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = stats::SimulatePower(
      p.name,
      [&pool, &model](int n, Rng& rng) {
        return design::SimulateRatings(pool, model.params, n, rng, true);
      },
      po);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::string line;
  for (const auto& c : p.criteria) {
    const int n = stats::ParticipantsFor(r, c, "method", 0.8);
    line += fmt::format("{}{}: {}", line.empty() ? "" : ", ", c,
                        n ? fmt::format("{}", n) : "more than 24");
  }
  // Named relative to the protocol (no absolute path in the output).
  const std::string observer =
      p.observer.empty()
          ? model.Describe()
          : fmt::format("the protocol's {} (sha256 {})", p.observer, model.sha256.substr(0, 16));
  fmt::print(
      "power: participants for 80 % power on the method effect (p < 0.05; {} simulated studies per "
      "count, "
      "{:.1f} s; observer {}; hapticlab study power): {}\n",
      po.simulations, s, observer, line);
}

// What the demo records: the study's --record modes, plus 'first' (all of the first
// participant, none of the others).
enum class DemoRecord { kFirst, kAll, kForce, kNone };
inline constexpr EnumTable<DemoRecord, 4> kDemoRecordNames{{{DemoRecord::kFirst, "first"},
                                                            {DemoRecord::kAll, "all"},
                                                            {DemoRecord::kForce, "force"},
                                                            {DemoRecord::kNone, "none"}}};

struct DemoArgs {
  std::string out,
      protocol = std::string(HL_SOURCE_DIR) + "/studies/shin2019/ch5-hybrid-realism.toml";
  int participants = 8;
  DemoRecord record = DemoRecord::kFirst;
};

// Runs the simulated participants SIM01.. into the database; what each felt goes to `pool`.
// Returns the seconds of stimuli simulated.
double RunParticipants(const protocols::Protocol& p, const DemoArgs& o, const std::string& db_path,
                       design::FeltPool* pool_out) {
  design::FeltPool& pool = *pool_out;
  double stimulus_s = 0;
  for (int i = 0; i < o.participants; ++i) {
    runner::RunOptions ro;
    ro.db_path = db_path;
    ro.participant = fmt::format("SIM{:02d}", i + 1);
    ro.record = o.record == DemoRecord::kAll || (o.record == DemoRecord::kFirst && i == 0)
                    ? runner::RecordMode::kAll
                : o.record == DemoRecord::kForce ? runner::RecordMode::kForce
                                                 : runner::RecordMode::kNone;
    ro.on_felt = [&pool, i](const runner::FeltTrial& t) {
      auto& v = pool.participants[static_cast<std::size_t>(i)];
      if (!v.empty() && v.back().plan_index == t.plan_index)
        v.back() = t;
      else
        v.push_back(t);
    };
    const auto s = runner::RunStudy(p, ro);
    stimulus_s += s.simulated_s;
    fmt::print("  {}: {} trials, {}\n", s.participant, s.completed,
               NameOf(db::kSessionStatusNames, s.status));
  }
  return stimulus_s;
}

int RunDemo(const DemoArgs& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const fs::path dir = fs::path(o.out.empty() ? "demo-out" : o.out) / UtcStamp();
  const auto p = protocols::LoadProtocol(o.protocol);  // before anything is written
  fs::create_directories(dir);
  const std::string db_path = (dir / "study.db").string();
  fmt::print("HapticLab {} ({}) demo: study '{}' with {} simulated participants -> {}\n", kVersion,
             kGitSha, p.name, o.participants, dir.string());
  // What the simulated participants felt: the physics pool of the power line at the end.
  design::FeltPool pool;
  pool.protocol = p.name;
  pool.criteria = p.criteria;
  pool.scale_min = p.scale_min;
  pool.scale_max = p.scale_max;
  pool.observer = design::ProtocolObserver(p);
  pool.participants.resize(static_cast<std::size_t>(o.participants));
  const double stimulus_s = RunParticipants(p, o, db_path, &pool);
  const auto report = stats::Analyze(db_path, {.out_dir = (dir / "report").string()});
  db::Database database(db_path, {.create = false, .read_only = true});
  // Trajectories stay in the database (`hapticlab export` writes them on request).
  const auto files = db::ExportCsv(database, (dir / "export").string(), false);
  const std::string timing = RealTimeCheck((fs::path(p.file).parent_path() / p.profiles).string());
  {
    std::ofstream md(report.markdown, std::ios::app);
    md << "\n## Real-time check\n\n" << timing;
    if (!md) throw std::runtime_error("cannot append the real-time check to " + report.markdown);
  }
  PowerLine(p, pool);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  fmt::print("\n{:.0f} s of stimuli simulated in {:.1f} s ({:.0f}x real time)\n", stimulus_s, wall,
             stimulus_s / wall);
  fmt::print("database: {}\nreport:   {}\nexport:   {} ({} CSV files)\n", db_path, report.markdown,
             (dir / "export").string(), files.size());
  fmt::print(
      "Models are placeholders derived from studies/shin2019/profiles.toml "
      "(docs/studies.md).\n");
  return kExitOk;
}

}  // namespace

void RegisterDemo(CLI::App& app) {
  auto o = std::make_shared<DemoArgs>();
  auto* cmd = app.add_subcommand(
      "demo",
      "The main job: a complete simulated study end to end. Runs the dissertation's ch. V.3\n"
      "protocol (hybrid vs force-only vs vibration-only) with simulated participants in the\n"
      "simulated lab (every trial through the real-time engine on a virtual clock, a simulated\n"
      "hand on a simulated device), records everything to a new database, analyses it into a\n"
      "report, and checks the engine on the real clock. Each run writes a new timestamped folder.");
  cmd->add_option("--out", o->out, "Parent folder of the run's output (default: demo-out)");
  cmd->add_option("--participants", o->participants, "Simulated participants")
      ->capture_default_str()
      ->check(CLI::Range(2, 100));
  cmd->add_option("--protocol", o->protocol, "Study protocol to run")->capture_default_str();
  AddEnumOption(cmd, "--record", o->record, kDemoRecordNames,
                "Trajectories to record: 'first' (every stream of the first participant, none of\n"
                "the others: keeps the database near 30 MB), 'all', 'force', 'none'");
  cmd->callback([o] { RunGuarded([&] { return RunDemo(*o); }); });
}

}  // namespace hapticlab::cli
