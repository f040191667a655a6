// hapticlab fit | compare | diagnose | effects | measurement: the model-versus-measurement
// workbench (DESIGN.md §4, docs/workbench.md).

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <filesystem>
#include <memory>
#include <set>
#include <mutex>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "fit_summary_json.hpp"
#include "commands.hpp"
#include "hapticlab/core/measurement.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/stats/plot.hpp"

namespace hapticlab::cli {
namespace {

using namespace modeling::wb;

nlohmann::json ErrorsJson(const Errors& e) {
  nlohmann::json j = {{"overall", e.overall}};
  for (const auto& [k, v] : e.channel) j["channels"][k] = v;
  for (const auto& [k, v] : e.rms) j["rms"][k] = v;
  return j;
}

std::string ErrorsLine(const Errors& e) {
  std::string s = fmt::format("overall {:.4f}", e.overall);
  for (const auto& [k, v] : e.channel) s += fmt::format(", {} {:.4f}", k, v);
  if (e.rms.count("normal_force_N"))
    s += fmt::format(" (rms: normal {:.4f} N, tangential {:.4f} N, friction ratio {:.4f})", e.rms.at("normal_force_N"),
                     e.rms.at("tangential_N"), e.rms.at("friction_ratio"));
  return s;
}

std::string Catalog() {
  std::string s;
  for (const auto& e : Catalogue()) s += (s.empty() ? "" : ", ") + std::string(e->name());
  return s;
}

Replay Load(const std::string& measurement, const Model* model) {
  const auto m = ReadMeasurementCsv(measurement);
  ReplayOptions o;
  if (model && model->HasVibration()) o.band_edges_hz = model->band_edges_hz;
  return PrepareReplay(m, o);
}

// ---------------------------------------------------------------------------------------------
// Progress lines on stderr (a person waits on fits of a minute); --quiet silences them.
struct Progress {
  bool quiet = false;
  std::mutex mu;
  void Line(const std::string& s) {
    if (quiet) return;
    std::lock_guard<std::mutex> lock(mu);
    fmt::print(stderr, "{}\n", s);
    std::fflush(stderr);
  }
};

nlohmann::json FitReportJson(const FitReport& rep) {
  nlohmann::json fits = nlohmann::json::array(), est;
  for (const auto& c : rep.channels) {
    fits.push_back(FitSummaryJson(c.summary));
    for (const auto& p : c.params)
      est[p.effect][p.name] = {{"value", p.value}, {"sd", p.sd}, {"lo95", p.lo95}, {"hi95", p.hi95}, {"at_bound", p.at_bound}};
  }
  return {{"fits", fits}, {"estimates", est}, {"usable", rep.IsUsable()}};
}

void AddFit(CLI::App& app) {
  struct O {
    std::string measurement, model, out;
    std::vector<std::string> add;
    bool json = false, quiet = false;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand(
      "fit",
      "Fit a material model to a measurement: the thesis's baseline (coulomb, viscous, dahl,\n"
      "hc-damping, hc-exponent, vibration-speed, vibration-force) when no --model is given,\n"
      "plus every --add effect. The contact channels use the same engine as `model fit-contact`\n"
      "(Algorithm 1, then a joint Ceres refinement of the vector Dahl replay). Prints the error\n"
      "(before and after when there is a change), on all data and held out (fitted on the even\n"
      "1 s blocks, scored on the odd ones), each solve's termination, iterations, cost and\n"
      "parameters at bounds, the parameters with 95 % intervals (cluster jackknife over\n"
      "3 s clusters of blocks), and writes the fitted model (a material TOML the renderer plays, with a\n"
      "[workbench] table of every parameter). Progress goes to stderr unless --quiet.");
  cmd->add_option("--measurement", o->measurement, "Measurement CSV v1 (with acc_mps2 for the vibration channel)")
      ->required();
  cmd->add_option("--model", o->model, "Start from this model (workbench or renderer material TOML)");
  cmd->add_option("--add", o->add, "Effect to add (repeatable); one of: " + Catalog());
  cmd->add_option("-o,--out", o->out, "Fitted model to write (.toml)")->required();
  cmd->add_flag("--json", o->json,
                "Print {before, after, held_out:{before, after}, effects, params, estimates, fits, usable} as JSON");
  cmd->add_flag("--quiet", o->quiet, "No progress lines on stderr");
  cmd->callback([o] {
    RunGuarded([&] {
      Progress prog;
      prog.quiet = o->quiet;
      Model start;
      const bool given = !o->model.empty();
      if (given) start = LoadModel(o->model);
      prog.Line(fmt::format("fit: reading {}", o->measurement));
      const auto r = Load(o->measurement, given ? &start : nullptr);
      if (!given) AddEffects(&start, BaselineEffects(), r);
      Model after = start;
      AddEffects(&after, o->add, r);
      // "Before" is the given model as it is, or (no --model) the baseline fitted; without
      // --add and --model, before and after are the same fit and are reported once.
      const bool changes = given || !o->add.empty();
      prog.Line("fit: fitting on all data (with uncertainties)");
      const auto rep = Fit(&after, r, {.uncertainty = true});
      const auto e_after = ComputeErrors(r, Predict(after, r), Split::kAll);
      Errors e_before = e_after;
      if (!given && !o->add.empty()) {
        Model before = start;
        prog.Line("fit: fitting the baseline on all data");
        Fit(&before, r);
        e_before = ComputeErrors(r, Predict(before, r), Split::kAll);
      } else if (given) {
        e_before = ComputeErrors(r, Predict(start, r), Split::kAll);
      }
      prog.Line("fit: fitting on the training blocks for the held-out errors");
      Model hb = start, ha = start;
      AddEffects(&ha, o->add, r);
      Fit(&ha, r, {.split = Split::kTrain});
      const auto h_after = ComputeErrors(r, Predict(ha, r), Split::kHeldOut);
      Errors h_before = h_after;
      if (!o->add.empty()) {
        Fit(&hb, r, {.split = Split::kTrain});
        h_before = ComputeErrors(r, Predict(hb, r), Split::kHeldOut);
      }
      if (after.name.empty()) after.name = std::filesystem::path(o->out).stem().string();
      SaveModel(after, o->out, &r);
      if (o->json) {
        nlohmann::json params;
        for (const auto& [e, ps] : after.params)
          for (const auto& [k, v] : ps) params[e][k] = v;
        auto j = nlohmann::json{{"before", ErrorsJson(e_before)},
                                {"after", ErrorsJson(e_after)},
                                {"held_out", {{"before", ErrorsJson(h_before)}, {"after", ErrorsJson(h_after)}}},
                                {"effects", after.effects},
                                {"params", params},
                                {"out", o->out}};
        j.update(FitReportJson(rep));
        fmt::print("{}\n", j.dump(2));
      } else {
        fmt::print("effects: {}\n", fmt::join(after.effects, ", "));
        if (changes) {
          fmt::print("before ({}): {}\n", given ? "model as given" : "baseline, fitted", ErrorsLine(e_before));
          fmt::print("after  (fitted):          {}\n", ErrorsLine(e_after));
          if (!o->add.empty()) fmt::print("held out, before: {}\n", ErrorsLine(h_before));
          fmt::print("held out{}: {}\n", o->add.empty() ? "" : ", after ", ErrorsLine(h_after));
        } else {
          fmt::print("fitted:   {}\n", ErrorsLine(e_after));
          fmt::print("held out: {}\n", ErrorsLine(h_after));
        }
        for (const auto& c : rep.channels) {
          fmt::print("{}\n", FitSummaryLine(c.summary));
          for (const auto& p : c.params)
            fmt::print("  {}.{} = {:.6g} +- {:.2g} (95 %: {:.6g} .. {:.6g}){}\n", p.effect, p.name, p.value, p.sd, p.lo95,
                       p.hi95, p.at_bound ? "  AT A BOUND" : "");
        }
        fmt::print("wrote {}\n", o->out);
      }
      if (!rep.IsUsable()) {
        fmt::print(stderr, "fit: a channel's fit is not usable (see the fit lines); {} was written for inspection\n", o->out);
        return kExitFailure;
      }
      return kExitOk;
    });
  });
}

// ---------------------------------------------------------------------------------------------
// Residual plots; with `before`, its residuals are drawn on the same axes (one plot per
// dimension and quantity, so before and after share their scales). Speed is on a log axis.
std::vector<std::string> Plots(const Comparison& c, const Model& m, const Replay& r, const std::string& dir,
                               const Comparison* before, const Model* before_model) {
  std::filesystem::create_directories(dir);
  std::vector<std::string> files;
  static const std::map<std::string, std::string> kUnit = {{"normal_force_N", "normal-force residual [N]"},
                                                           {"friction_N", "friction residual along the motion [N]"},
                                                           {"friction_ratio", "friction-ratio residual"},
                                                           {"vibration_dB", "band-power residual [dB]"}};
  static const std::map<std::string, std::string> kX = {{"regime", "regime (0 pre-sliding, 1 transition, 2 sliding)"},
                                                        {"speed", "log10 speed [mm/s]"},
                                                        {"load", "normal force [N]"},
                                                        {"direction", "direction of motion [deg]"},
                                                        {"position", "tile (0-2 front, 3-5 middle, 6-8 back)"},
                                                        {"time", "time [tenths of the measurement]"},
                                                        {"band", "band centre [Hz]"}};
  for (const auto& [dim, qs] : c.breakdown)
    for (const auto& [q, rows] : qs) {
      const std::vector<BinRow>* brow = nullptr;
      if (before && before->breakdown.count(dim) && before->breakdown.at(dim).count(q)) brow = &before->breakdown.at(dim).at(q);
      stats::LinePlot p;
      p.title = fmt::format("{} by {}", q, dim);
      p.x_label = kX.count(dim) ? kX.at(dim) : dim;
      p.y_label = kUnit.count(q) ? kUnit.at(q) : q;
      std::vector<double> mean, rms, bmean, brms;
      for (std::size_t k = 0; k < rows.size(); ++k) {
        if (rows[k].n == 0) continue;
        double x = static_cast<double>(k);
        if (dim == "load" || dim == "band") x = rows[k].center;
        if (dim == "speed") x = std::log10(std::max(rows[k].center, 0.1));
        if (dim == "direction") x = -180 + 45.0 * static_cast<double>(k);
        p.x.push_back(x);
        mean.push_back(rows[k].mean);
        rms.push_back(rows[k].rms);
        if (brow && k < brow->size()) bmean.push_back((*brow)[k].mean), brms.push_back((*brow)[k].rms);
      }
      if (p.x.size() < 2) continue;
      if (brow && bmean.size() == mean.size()) {
        p.series = {{"mean", mean}, {"RMS", rms}, {"mean (before)", bmean}, {"RMS (before)", brms}};
      } else {
        p.series = {{"mean", mean}, {"RMS", rms}};
      }
      for (const auto& f : stats::DrawLinePlot(p, (std::filesystem::path(dir) / fmt::format("residual_{}_{}", dim, q)).string()))
        files.push_back(f);
    }
  // Traces: measured and predicted forces over the first 5 s.
  const auto pred = Predict(m, r);
  Prediction bpred;
  if (before_model) bpred = Predict(*before_model, r);
  stats::LinePlot fn{"normal force, measured and model", "time [s]", "force [N]", {}, {}, false};
  stats::LinePlot ft{"friction along the motion, measured and model", "time [s]", "force [N]", {}, {}, false};
  std::vector<double> a, b, b0, c2, d, d0;
  for (std::size_t i = 0; i < r.s.size() && r.s[i].t_s < r.s.front().t_s + 5; ++i) {
    const auto& s = r.s[i];
    fn.x.push_back(s.t_s);
    a.push_back(s.fn_N);
    b.push_back(pred.fn_N[i]);
    ft.x.push_back(s.t_s);
    const double ux = s.speed_mps > 5e-4 ? s.vx_mps / s.speed_mps : 0, uy = s.speed_mps > 5e-4 ? s.vy_mps / s.speed_mps : 0;
    c2.push_back(-(s.ftx_N * ux + s.fty_N * uy));
    d.push_back(-(pred.ftx_N[i] * ux + pred.fty_N[i] * uy));
    if (before_model) {
      b0.push_back(bpred.fn_N[i]);
      d0.push_back(-(bpred.ftx_N[i] * ux + bpred.fty_N[i] * uy));
    }
  }
  fn.series = {{"measured", a}, {"model", b}};
  ft.series = {{"measured", c2}, {"model", d}};
  if (before_model) {
    fn.series.push_back({"model (before)", b0});
    ft.series.push_back({"model (before)", d0});
  }
  if (fn.x.size() > 1) {
    for (const auto& f : stats::DrawLinePlot(fn, (std::filesystem::path(dir) / "trace_normal_force").string())) files.push_back(f);
    for (const auto& f : stats::DrawLinePlot(ft, (std::filesystem::path(dir) / "trace_friction").string())) files.push_back(f);
  }
  return files;
}

// The largest systematic residuals of a comparison: bins whose mean residual is largest against
// the quantity's RMS over all bins.
struct Failure {
  std::string dimension, quantity, bin;
  int n = 0;
  double mean = 0, rms = 0, score = 0;
};
std::vector<Failure> LargestFailures(const Comparison& c, std::size_t count) {
  std::map<std::string, double> total, nq;
  for (const auto& [dim, qs] : c.breakdown)
    for (const auto& [q, rows] : qs)
      if (dim == "regime" || (q == "vibration_dB" && dim == "band"))
        for (const auto& row : rows) total[q] += row.rms * row.rms * row.n, nq[q] += row.n;
  std::vector<Failure> all;
  for (const auto& [dim, qs] : c.breakdown)
    for (const auto& [q, rows] : qs) {
      const double ref = nq[q] > 0 ? std::sqrt(total[q] / nq[q]) : 0;
      for (const auto& row : rows)
        if (row.n >= 50 && ref > 0)
          all.push_back({dim, q, row.label, row.n, row.mean, row.rms, std::abs(row.mean) / ref});
    }
  std::stable_sort(all.begin(), all.end(), [](const Failure& a, const Failure& b) { return a.score > b.score; });
  std::vector<Failure> out;
  std::set<std::pair<std::string, std::string>> seen;  // one bin per dimension and quantity
  for (const auto& f : all)
    if (out.size() < count && seen.insert({f.dimension, f.quantity}).second) out.push_back(f);
  return out;
}

void AddCompare(CLI::App& app) {
  struct O {
    std::string measurement, model, plots, before;
    bool json = false;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand(
      "compare",
      "Replay a measurement's kinematics through a model and report its errors. It opens with a\n"
      "summary: the error per channel (normal force, tangential force, vibration E_s), where the\n"
      "residual lives (share of each channel's residual variance along time, speed, load,\n"
      "direction, position, regime and band, with the shape in words) and the largest systematic\n"
      "residuals; the breakdown bin by bin follows. --plots draws the residual against each\n"
      "dimension (speed on a log axis); with --before, an earlier model's residuals are drawn on\n"
      "the same axes.");
  cmd->add_option("--model", o->model, "Model (workbench or renderer material TOML)")->required();
  cmd->add_option("--measurement", o->measurement, "Measurement CSV v1")->required();
  cmd->add_flag("--json", o->json,
                "Print {\"error\": x, \"channels\": {...}, \"summary\": {\"axes\", \"largest\"}, \"breakdown\": {...}}");
  cmd->add_option("--plots", o->plots, "Folder for residual plots (SVG and PNG)");
  cmd->add_option("--before", o->before, "An earlier model whose residuals the plots show on the same axes");
  cmd->callback([o] {
    RunGuarded([&] {
      const auto m = LoadModel(o->model);
      const auto r = Load(o->measurement, &m);
      const auto c = Compare(m, r);
      const auto axes = RankResidualAxes(m, r, Predict(m, r));
      const auto largest = LargestFailures(c, 5);
      std::vector<std::string> files;
      if (!o->plots.empty()) {
        if (!o->before.empty()) {
          const auto mb = LoadModel(o->before);
          const auto cb = Compare(mb, r);
          files = Plots(c, m, r, o->plots, &cb, &mb);
        } else {
          files = Plots(c, m, r, o->plots, nullptr, nullptr);
        }
      }
      if (o->json) {
        nlohmann::json b, ax = nlohmann::json::array(), lg = nlohmann::json::array();
        for (const auto& [dim, qs] : c.breakdown)
          for (const auto& [q, rows] : qs)
            for (const auto& row : rows)
              b[dim][q].push_back({{"bin", row.label}, {"n", row.n}, {"mean", row.mean}, {"rms", row.rms}});
        for (const auto& x : axes)
          ax.push_back({{"axis", x.axis}, {"channel", x.channel}, {"share", x.share}, {"description", x.description}});
        for (const auto& f : largest)
          lg.push_back({{"dimension", f.dimension}, {"quantity", f.quantity}, {"bin", f.bin}, {"n", f.n}, {"mean", f.mean},
                        {"rms", f.rms}});
        auto j = ErrorsJson(c.errors);
        fmt::print("{}\n", nlohmann::json{{"error", c.errors.overall},
                                          {"channels", j["channels"]},
                                          {"rms", j["rms"]},
                                          {"summary", {{"axes", ax}, {"largest", lg}}},
                                          {"breakdown", b},
                                          {"plots", files}}
                               .dump(2));
        return kExitOk;
      }
      fmt::print("{} on {}: {}\n", o->model, o->measurement, ErrorsLine(c.errors));
      fmt::print("\nwhere the residual lives (share of each channel's residual variance):\n");
      for (std::size_t k = 0; k < axes.size() && k < 5; ++k)
        fmt::print("  {:9s} {:13s} {:5.1f} %  {}\n", axes[k].axis, axes[k].channel, 100 * axes[k].share, axes[k].description);
      fmt::print("\nlargest systematic residuals:\n");
      for (const auto& f : largest)
        fmt::print("  {} by {}, {}: mean {:+.4f}, rms {:.4f} (n {})\n", f.quantity, f.dimension, f.bin, f.mean, f.rms, f.n);
      fmt::print("\ndetail:\n");
      for (const auto& [dim, qs] : c.breakdown)
        for (const auto& [q, rows] : qs) {
          fmt::print("\n{} by {}:\n", q, dim);
          for (const auto& row : rows)
            if (row.n) fmt::print("  {:28s} n {:6d}  mean {:+.4f}  rms {:.4f}\n", row.label, row.n, row.mean, row.rms);
        }
      if (!files.empty()) fmt::print("\nplots: {} files in {}\n", files.size(), o->plots);
      return kExitOk;
    });
  });
}

// ---------------------------------------------------------------------------------------------
void AddDiagnose(CLI::App& app) {
  struct O {
    std::string measurement, model;
    bool json = false, quiet = false;
    int threads = 0;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand(
      "diagnose",
      "For every catalogue effect the model lacks: add it, fit on the training blocks (even 1 s\n"
      "blocks) and score on the held-out blocks; rank by held-out error reduction. An effect is\n"
      "supported when its channel's held-out error falls by at least 2 %, the per-block paired t\n"
      "(log error ratio) is at least 3, its fit converged with none of its parameters at a bound,\n"
      "and the residual pattern it produces is there; only then does its evidence name a cause.\n"
      "Supported effects that change the prediction the same way are reported as confounded.\n"
      "Then what is unexplained: each channel's held-out error against its noise floor (estimated\n"
      "from the measurement) and where the residual lives (time, speed, load, direction, position,\n"
      "regime, band; share of its variance, shape in words). When nothing is supported but an\n"
      "error is 1.5x its floor or more, that is said first. Progress on stderr unless --quiet.");
  cmd->add_option("--model", o->model, "Model (workbench or renderer material TOML)")->required();
  cmd->add_option("--measurement", o->measurement, "Measurement CSV v1")->required();
  cmd->add_flag("--json", o->json,
                "Print {\"baseline_error\", \"candidates\": [{effect, error_after, error_reduction, params, "
                "evidence, fit, rejected, ...}], \"unexplained\": {\"channels\": [...], \"axes\": [...]}}");
  cmd->add_flag("--quiet", o->quiet, "No progress on stderr");
  cmd->add_option("--threads", o->threads, "Candidates fitted in parallel (0: all cores)")->capture_default_str();
  cmd->callback([o] {
    RunGuarded([&] {
      const auto m = LoadModel(o->model);
      const auto r = Load(o->measurement, &m);
      std::mutex mu;
      DiagnoseOptions opt;
      opt.threads = o->threads;
      const bool tty = isatty(fileno(stderr));
      if (!o->quiet) {
        fmt::print(stderr, "diagnose: refitting {} on the training blocks, then each candidate\n", o->model);
        opt.progress = [&, tty](const std::string& effect, int done, int total) {
          std::lock_guard<std::mutex> lock(mu);
          if (tty) {
            const int w = 30, filled = w * done / std::max(total, 1);
            fmt::print(stderr, "\rdiagnose [{}{}] {}/{} ({}){:20s}", std::string(filled, '#'), std::string(w - filled, '.'),
                       done, total, effect, "");
            if (done == total) fmt::print(stderr, "\n");
          } else {
            fmt::print(stderr, "diagnose: {}/{} candidates fitted ({})\n", done, total, effect);
          }
        };
      }
      const auto dx = Diagnose(m, r, opt);
      const auto& u = dx.unexplained;
      if (o->json) {
        nlohmann::json c = nlohmann::json::array();
        for (const auto& x : dx.candidates)
          c.push_back({{"effect", x.effect},
                       {"channel", x.channel},
                       {"error_after", x.error_after},
                       {"error_reduction", x.error_reduction},
                       {"relative_reduction", x.relative_reduction},
                       {"t", x.t_statistic},
                       {"supported", x.supported},
                       {"params", x.params},
                       {"evidence", x.evidence},
                       {"confounded_with", x.confounded_with},
                       {"fit", FitSummaryJson(x.fit)},
                       {"rejected", x.rejected}});
        nlohmann::json ch = nlohmann::json::array(), ax = nlohmann::json::array();
        for (const auto& x : u.channels)
          ch.push_back({{"channel", x.channel}, {"error", x.error}, {"noise_floor", x.noise_floor}, {"ratio", x.ratio}});
        for (const auto& x : u.axes)
          ax.push_back({{"axis", x.axis}, {"channel", x.channel}, {"share", x.share}, {"description", x.description}});
        fmt::print("{}\n", nlohmann::json{{"baseline_error", dx.baseline_error},
                                          {"baseline_channels", dx.baseline_channel},
                                          {"candidates", c},
                                          {"unexplained",
                                           {{"channels", ch}, {"axes", ax}, {"flagged", u.flagged}, {"summary", u.summary}}}}
                               .dump(2));
        return kExitOk;
      }
      if (u.flagged) fmt::print("{}\n\n", u.summary);
      fmt::print("held-out error of {} (refitted on the training blocks): {:.4f}", o->model, dx.baseline_error);
      for (const auto& [k, v] : dx.baseline_channel) fmt::print(", {} {:.4f}", k, v);
      fmt::print("\n\n");
      int rank = 0;
      for (const auto& x : dx.candidates) {
        fmt::print("{}. {} ({}): held-out error {:.4f} ({:+.4f}; {} error {:+.1f} %, t = {:.1f}) {}\n", ++rank, x.effect,
                   x.channel, x.error_after, -x.error_reduction, x.channel, -100 * x.relative_reduction, x.t_statistic,
                   x.supported ? "SUPPORTED" : "not supported");
        fmt::print("   {}\n", x.evidence);
        if (x.supported) {
          std::string ps;
          for (const auto& [k, v] : x.params) ps += fmt::format("{}{} = {:.4g}", ps.empty() ? "" : ", ", k, v);
          fmt::print("   fitted: {}\n", ps);
        }
      }
      fmt::print("\nunexplained (held-out error against the noise floor estimated from the measurement):\n");
      for (const auto& x : u.channels)
        fmt::print("  {:13s} error {:.4f}, floor {:.4f}, {:.1f}x\n", x.channel, x.error, x.noise_floor, x.ratio);
      fmt::print("where the residual lives (share of a channel's residual variance along each axis):\n");
      for (std::size_t k = 0; k < u.axes.size() && k < 6; ++k)
        fmt::print("  {:9s} {:13s} {:5.1f} %  {}\n", u.axes[k].axis, u.axes[k].channel, 100 * u.axes[k].share,
                   u.axes[k].description);
      if (!u.flagged) fmt::print("{}\n", u.summary);
      return kExitOk;
    });
  });
}

// ---------------------------------------------------------------------------------------------
void AddEffectsList(CLI::App& app) {
  auto json = std::make_shared<bool>(false);
  auto* cmd = app.add_subcommand("effects", "List the workbench's catalogue of physical effects with their parameters");
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
        if (e->VibrationColumns()) line += fmt::format("{}{} coefficients per band", line.empty() ? "" : ", ", e->VibrationColumns());
        j.push_back({{"name", e->name()}, {"channel", ChannelName(e->channel())}, {"params", ps},
                     {"requires", e->requires_effects()}, {"description", e->description()}});
        if (!*json)
          fmt::print("{} ({}{}): {}\n  parameters: {}\n\n", e->name(), ChannelName(e->channel()),
                     e->requires_effects().empty() ? "" : fmt::format(", needs {}", fmt::join(e->requires_effects(), ", ")),
                     e->description(), line);
      }
      if (*json) fmt::print("{}\n", j.dump(2));
      else fmt::print("baseline (the thesis's model): {}\n", fmt::join(BaselineEffects(), ", "));
      return kExitOk;
    });
  });
}

// ---------------------------------------------------------------------------------------------
void AddMeasurement(CLI::App& app) {
  auto* grp = app.add_subcommand("measurement", "Check or simulate measurement CSV v1 files");
  grp->require_subcommand(1);
  {
    struct O {
      std::string file;
      bool json = false;
    };
    auto o = std::make_shared<O>();
    auto* cmd = grp->add_subcommand("check",
                                    "Read a measurement CSV v1 (errors name file, line and column) and summarize it:\n"
                                    "duration, rate, ranges per column, gaps, samples in contact, warnings.");
    cmd->add_option("FILE", o->file, "Measurement CSV v1")->required();
    cmd->add_flag("--json", o->json, "As JSON");
    cmd->callback([o] {
      RunGuarded([&] {
        const auto m = ReadMeasurementCsv(o->file);
        const auto s = Summarize(m);
        if (o->json) {
          nlohmann::json ranges;
          for (const auto& [k, v] : s.ranges) ranges[k] = {v.first, v.second};
          fmt::print("{}\n", nlohmann::json{{"file", o->file},
                                            {"material", m.material},
                                            {"samples", s.samples},
                                            {"duration_s", s.duration_s},
                                            {"rate_hz", s.rate_hz},
                                            {"gaps", s.gaps},
                                            {"max_gap_s", s.max_gap_s},
                                            {"contact_samples", s.contact_samples},
                                            {"has_acceleration", m.has_acceleration},
                                            {"ranges", ranges},
                                            {"warnings", s.warnings}}
                                 .dump(2));
          return kExitOk;
        }
        fmt::print("{}: material '{}', {} samples, {:.3f} s at {:.1f} Hz, {} in contact, {} gap{} (longest {:.4g} s)\n",
                   o->file, m.material, s.samples, s.duration_s, s.rate_hz, s.contact_samples, s.gaps, s.gaps == 1 ? "" : "s",
                   s.max_gap_s);
        for (const auto& [k, v] : s.ranges) fmt::print("  {:9s} {:+.6g} .. {:+.6g}\n", k, v.first, v.second);
        for (const auto& w : s.warnings) fmt::print("warning: {}\n", w);
        return kExitOk;
      });
    });
  }
  {
    struct O {
      std::string out;
      std::vector<std::string> effects, add;
      double duration_s = 120, rate_hz = 2000;
      std::uint64_t seed = 1;
    };
    auto o = std::make_shared<O>();
    auto* cmd = grp->add_subcommand(
        "simulate",
        "Write a measurement of simulated human-like strokes (2-150 mm/s, 0.3-2.5 N, pauses, lift-offs)\n"
        "on a ground-truth sample with the given effects (default: the baseline's), with sensor\n"
        "noise. For learning the workbench and testing a pipeline; the seed is recorded in the file.");
    cmd->add_option("-o,--out", o->out, "Measurement CSV v1 to write")->required();
    cmd->add_option("--effects", o->effects, "The truth's effects (default: the baseline's)");
    cmd->add_option("--add", o->add, "Effects on top of the baseline's (repeatable)");
    cmd->add_option("--duration", o->duration_s, "Length [s]")->capture_default_str()->check(CLI::Range(5.0, 3600.0));
    cmd->add_option("--rate", o->rate_hz, "Sample rate [Hz]")->capture_default_str()->check(CLI::Range(1000.0, 20000.0));
    cmd->add_option("--seed", o->seed, "Seed of every random draw")->capture_default_str();
    cmd->callback([o] {
      RunGuarded([&] {
        TruthParams t;
        t.effects = o->effects.empty() ? BaselineEffects() : o->effects;
        for (const auto& e : o->add) t.effects.push_back(e);
        for (const auto& e : t.effects)
          if (!FindEffect(e)) throw std::invalid_argument(fmt::format("unknown effect '{}'; the catalogue has: {}", e, Catalog()));
        t.duration_s = o->duration_s;
        t.rate_hz = o->rate_hz;
        t.seed = o->seed;
        auto sim = Simulate(t);
        sim.m.material = "simulated";
        WriteMeasurementCsv(o->out, sim.m);
        fmt::print("wrote {} ({} samples, truth: {}, seed {})\n", o->out, sim.m.rows.size(), fmt::join(t.effects, ", "),
                   t.seed);
        return kExitOk;
      });
    });
  }
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
