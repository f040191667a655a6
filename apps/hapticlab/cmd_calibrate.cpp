// hapticlab study calibrate: fits the simulated observer's parameters (sim::ObserverParams)
// to published summary statistics (docs/studies.md "Calibrating the observer"). The physics
// of each protocol is recorded once through the runner (design::RecordFeltPool); every
// evaluation re-rates it with the candidate observer for a fixed set of simulated studies
// (common random numbers: the same seeds for every candidate, so the loss is a smooth
// function of the parameters) and compares the statistics with their targets.
// Optimiser: a hand-written compass (coordinate pattern) search with step halving (Torczon
// 1997); the loss is a Monte-Carlo average, so a derivative-free search is the simple choice.

#include <fmt/core.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <thread>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/design/calibration.hpp"
#include "hapticlab/design/power_pool.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/stats/power.hpp"

namespace hapticlab::cli {
namespace {

namespace fs = std::filesystem;

struct CalArgs {
  std::string targets, out;
  bool quiet = false;
};

// The free parameters: global ones, then four per criterion.
struct Param {
  std::string name;  // "range_sd", "roughness.sensitivity", ...
  double lo, hi, step;
};

double& Ref(sim::ObserverParams& o, const std::string& name) {
  if (name == "upper") return o.upper;
  if (name == "lower") return o.lower;
  if (name == "range_sd") return o.range_sd;
  if (name == "lapse_rate") return o.lapse_rate;
  if (name == "scale_vibration") return o.scale_vibration;
  if (name == "scale_fluctuation") return o.scale_fluctuation;
  if (name == "scale_friction") return o.scale_friction;
  if (name == "scale_stiffness") return o.scale_stiffness;
  if (name == "scale_pattern") return o.scale_pattern;
  const auto dot = name.find('.');
  auto& c = o.criteria[name.substr(0, dot)];
  const std::string f = name.substr(dot + 1);
  if (f == "sensitivity") return c.sensitivity;
  if (f == "offset_sd") return c.offset_sd;
  if (f == "material_sd") return c.material_sd;
  if (f == "method_sd") return c.method_sd;
  return c.noise_sd;
}

std::string ObserverToml(const sim::ObserverParams& o, const std::string& header) {
  std::string s = header;
  s += fmt::format(
      "[observer]\nupper = {:.3f}\nlower = {:.3f}\nrange_sd = {:.4f}\nlapse_rate = {:.4f}\n",
      o.upper, o.lower, o.range_sd, o.lapse_rate);
  s += fmt::format(
      "scale_vibration = {:.4f}\nscale_fluctuation = {:.4f}\nscale_friction = {:.4f}\n"
      "scale_stiffness = {:.4f}\nscale_pattern = {:.4f}\n",
      o.scale_vibration, o.scale_fluctuation, o.scale_friction, o.scale_stiffness, o.scale_pattern);
  s += fmt::format(
      "sensitivity = {:.4f}\noffset_sd = {:.3f}\nmaterial_sd = {:.3f}\nmethod_sd = "
      "{:.3f}\nnoise_sd = {:.3f}\n",
      o.defaults.sensitivity, o.defaults.offset_sd, o.defaults.material_sd, o.defaults.method_sd,
      o.defaults.noise_sd);
  for (const auto& [name, c] : o.criteria)
    s += fmt::format(
        "\n[criterion.{}]\nsensitivity = {:.4f}\noffset_sd = {:.3f}\nmaterial_sd = "
        "{:.3f}\nmethod_sd = {:.3f}\n"
        "noise_sd = {:.3f}\n",
        name, c.sensitivity, c.offset_sd, c.material_sd, c.method_sd, c.noise_sd);
  return s;
}

// The compass search from `best` (clamped to the bounds first): per sweep, each parameter's
// first step (up, then down) that lowers the loss is taken; a sweep without one halves every
// step. Returns the best loss; `best` holds its parameters.
double CompassSearch(const design::CalibrationState& st, const design::CalibrationSpec& spec,
                     const std::function<void(const std::string&)>& log,
                     sim::ObserverParams* best_out) {
  sim::ObserverParams& best = *best_out;
  std::vector<Param> params;
  for (const auto& p : spec.params) params.push_back({p.name, p.lo, p.hi, p.step});
  for (const auto& p : params) Ref(best, p.name) = std::clamp(Ref(best, p.name), p.lo, p.hi);
  double best_loss = design::EvaluateCalibration(st, spec, best, nullptr);
  log(fmt::format("start: loss {:.4f}", best_loss));
  for (int sweep = 0; sweep < spec.sweeps; ++sweep) {
    bool improved = false;
    for (auto& p : params) {
      for (const double dir : {+1.0, -1.0}) {
        sim::ObserverParams cand = best;
        double& v = Ref(cand, p.name);
        const double nv = std::clamp(v + dir * p.step, p.lo, p.hi);
        if (nv == v) continue;
        v = nv;
        const double l = design::EvaluateCalibration(st, spec, cand, nullptr);
        if (l < best_loss) {
          best_loss = l;
          best = cand;
          improved = true;
          break;
        }
      }
    }
    if (!improved)
      for (auto& p : params) p.step *= 0.5;
    log(fmt::format("sweep {}: loss {:.4f}{}", sweep + 1, best_loss,
                    improved ? "" : " (steps halved)"));
  }
  return best_loss;
}

// The observer file's header: how it was written and what its keys mean.
std::string ObserverHeader(const CalArgs& a, const design::CalibrationSpec& spec,
                           double final_loss) {
  return fmt::format(
      "# The simulated observer of the dissertation's studies (sim::Observer; docs/studies.md\n"
      "# \"The simulated observer\"). WRITTEN BY `hapticlab study calibrate {}`\n"
      "# (seed {}, {} simulated studies per protocol per evaluation, pools of {}, {} sweeps; "
      "loss {:.4f}).\n"
      "# A rating on criterion c of a trial with material m and method k:\n"
      "#   s0 = lower + (upper - lower) exp(-(sensitivity_c d_c)^2 / 2)     latent similarity\n"
      "#   s  = mid + r (s0 - mid) + o_c + u_cm + v_ck + e                  mid = scale "
      "midpoint\n"
      "# r = exp(N(0, range_sd)): the participant's use of the scale's range; o_c ~ N(0, "
      "offset_sd),\n"
      "# u_cm ~ N(0, material_sd), v_ck ~ N(0, method_sd): offset and participant x material / "
      "x method\n"
      "# effects; e ~ N(0, noise_sd) per rating; with probability lapse_rate a rating is "
      "uniform on\n"
      "# the scale. d_c: feature distance of what the hand felt on the two sides (scale_* "
      "below).\n"
      "# Keys in [observer] are the defaults of every criterion without a [criterion.NAME] "
      "table.\n\n",
      fs::path(a.targets).filename().string(), spec.seed, spec.simulations, spec.pool, spec.sweeps,
      final_loss);
}

int RunCalibrate(const CalArgs& a) {
  const auto spec = design::LoadCalibration(a.targets);
  const auto log = StderrLog(a.quiet);
  design::CalibrationState st = design::PrepareCalibration(spec, log);
  sim::ObserverParams best = st.start;
  CompassSearch(st, spec, log, &best);
  std::vector<design::CalibrationRow> rows;
  const double final_loss = design::EvaluateCalibration(st, spec, best, &rows);
  const std::string out = a.out.empty() ? spec.observer_out : a.out;
  WriteTextFile(out, ObserverToml(best, ObserverHeader(a, spec, final_loss)));
  fmt::print("| protocol | statistic | target | weight | achieved |\n|---|---|---|---|---|\n");
  for (const auto& r : rows)
    fmt::print("| {} | {} | {:.3f} | {:g} | {:.3f} |\n", r.protocol, r.label, r.target, r.weight,
               r.achieved);
  fmt::print("\nloss {:.4f}; observer written to {}\n", final_loss, out);
  return kExitOk;
}

}  // namespace

void RegisterCalibrate(CLI::App& study) {
  auto a = std::make_shared<CalArgs>();
  auto* cmd = study.add_subcommand(
      "calibrate",
      "Fit the simulated observer (range, offsets, participant x material / x method effects, "
      "noise,\n"
      "criterion sensitivity, perceptual cue scales) to published statistics: partial eta^2,\n"
      "method means, SDs, real-real limits, listed with weights in a targets file\n"
      "(studies/shin2019/calibration.toml). Writes an observer file and prints the targets,\n"
      "weights and achieved values. Reproducible from the targets file's seed.");
  cmd->add_option("TARGETS", a->targets, "Calibration targets (.toml)")->required();
  cmd->add_option("--out", a->out,
                  "Observer file to write (default: the targets file's `observer`)");
  cmd->add_flag("--quiet", a->quiet, "No progress on stderr");
  cmd->callback([a] { RunGuarded([&] { return RunCalibrate(*a); }); });
}

}  // namespace hapticlab::cli
