// hapticlab compare: a model's errors against a measurement, by regime, with residual plots
// (docs/workbench.md).

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>

#include "cli_common.hpp"
#include "commands.hpp"
#include "fit_summary_json.hpp"
#include "hapticlab/core/measurement.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/stats/plot.hpp"
#include "workbench_cli.hpp"

namespace hapticlab::cli::workbench_cli {

using namespace modeling::wb;

namespace {

// ---------------------------------------------------------------------------------------------
// Residual plots; with `before`, its residuals are drawn on the same axes (one plot per
// dimension and quantity, so before and after share their scales). Speed is on a log axis.
void ResidualPlots(const Comparison& c, const std::string& dir, const Comparison* before,
                   std::vector<std::string>* files) {
  static const std::map<std::string, std::string> kUnit = {
      {"normal_force_N", "normal-force residual [N]"},
      {"friction_N", "friction residual along the motion [N]"},
      {"friction_ratio", "friction-ratio residual"},
      {"vibration_dB", "band-power residual [dB]"}};
  static const std::map<std::string, std::string> kX = {
      {"regime", "regime (0 pre-sliding, 1 transition, 2 sliding)"},
      {"speed", "log10 speed [mm/s]"},
      {"load", "normal force [N]"},
      {"direction", "direction of motion [deg]"},
      {"position", "tile (0-2 front, 3-5 middle, 6-8 back)"},
      {"time", "time [tenths of the measurement]"},
      {"band", "band centre [Hz]"}};
  for (const auto& [dim, qs] : c.breakdown)
    for (const auto& [q, rows] : qs) {
      const std::vector<BinRow>* brow = nullptr;
      if (before && before->breakdown.count(dim) && before->breakdown.at(dim).count(q))
        brow = &before->breakdown.at(dim).at(q);
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
        if (brow && k < brow->size())
          bmean.push_back((*brow)[k].mean), brms.push_back((*brow)[k].rms);
      }
      if (p.x.size() < 2) continue;
      if (brow && bmean.size() == mean.size()) {
        p.series = {{"mean", mean}, {"RMS", rms}, {"mean (before)", bmean}, {"RMS (before)", brms}};
      } else {
        p.series = {{"mean", mean}, {"RMS", rms}};
      }
      for (const auto& f : stats::DrawLinePlot(
               p, (std::filesystem::path(dir) / fmt::format("residual_{}_{}", dim, q)).string()))
        files->push_back(f);
    }
}

// Traces: measured and predicted forces over the first 5 s (with `before_model`'s too).
void TracePlots(const Model& m, const Replay& r, const std::string& dir, const Model* before_model,
                std::vector<std::string>* files) {
  const auto pred = Predict(m, r);
  Prediction bpred;
  if (before_model) bpred = Predict(*before_model, r);
  stats::LinePlot fn{"normal force, measured and model", "time [s]", "force [N]", {}, {}, false};
  stats::LinePlot ft{
      "friction along the motion, measured and model", "time [s]", "force [N]", {}, {}, false};
  std::vector<double> a, b, b0, c2, d, d0;
  for (std::size_t i = 0;
       i < r.samples().size() && r.samples()[i].t_s < r.samples().front().t_s + 5; ++i) {
    const auto& s = r.samples()[i];
    fn.x.push_back(s.t_s);
    a.push_back(s.fn_N);
    b.push_back(pred.fn_N[i]);
    ft.x.push_back(s.t_s);
    const double ux = s.speed_mps > 5e-4 ? s.vx_mps / s.speed_mps : 0,
                 uy = s.speed_mps > 5e-4 ? s.vy_mps / s.speed_mps : 0;
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
    for (const auto& f :
         stats::DrawLinePlot(fn, (std::filesystem::path(dir) / "trace_normal_force").string()))
      files->push_back(f);
    for (const auto& f :
         stats::DrawLinePlot(ft, (std::filesystem::path(dir) / "trace_friction").string()))
      files->push_back(f);
  }
}

// The residual and trace plots in `dir`; returns the files written.
std::vector<std::string> Plots(const Comparison& c, const Model& m, const Replay& r,
                               const std::string& dir, const Comparison* before,
                               const Model* before_model) {
  std::filesystem::create_directories(dir);
  std::vector<std::string> files;
  ResidualPlots(c, dir, before, &files);
  TracePlots(m, r, dir, before_model, &files);
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
  std::stable_sort(all.begin(), all.end(),
                   [](const Failure& a, const Failure& b) { return a.score > b.score; });
  std::vector<Failure> out;
  std::set<std::pair<std::string, std::string>> seen;  // one bin per dimension and quantity
  for (const auto& f : all)
    if (out.size() < count && seen.insert({f.dimension, f.quantity}).second) out.push_back(f);
  return out;
}

struct CompareArgs {
  std::string measurement, model, plots, before;
  bool json = false;
};

// What `compare` found, to print.
struct CompareReport {
  Comparison c;
  std::vector<EsCell> es_cells;
  std::vector<ResidualAxis> axes;
  std::vector<Failure> largest;
  std::vector<std::string> files;
  std::string vib_note;
};

void PrintCompareJson(const CompareReport& x) {
  const Comparison& c = x.c;
  nlohmann::json b, ax = nlohmann::json::array(), lg = nlohmann::json::array();
  for (const auto& [dim, qs] : c.breakdown)
    for (const auto& [q, rows] : qs)
      for (const auto& row : rows)
        b[dim][q].push_back(
            {{"bin", row.label}, {"n", row.n}, {"mean", row.mean}, {"rms", row.rms}});
  for (const auto& a : x.axes)
    ax.push_back({{"axis", a.axis},
                  {"channel", ChannelName(a.channel)},
                  {"share", a.share},
                  {"description", a.description}});
  for (const auto& f : x.largest)
    lg.push_back({{"dimension", f.dimension},
                  {"quantity", f.quantity},
                  {"bin", f.bin},
                  {"n", f.n},
                  {"mean", f.mean},
                  {"rms", f.rms}});
  auto j = ErrorsJson(c.errors);
  PrintJson(nlohmann::json{{"error", c.errors.overall},
                           {"channels", j["channels"]},
                           {"rms", j["rms"]},
                           {"summary", {{"axes", ax}, {"largest", lg}}},
                           {"breakdown", b},
                           {"plots", x.files},
                           {"vibration_model", x.vib_note},
                           {"vibration_by_condition", EsCellsJson(x.es_cells)}});
}

void PrintCompare(const CompareArgs& o, const CompareReport& x) {
  const Comparison& c = x.c;
  fmt::print("{} on {}: {}\n", o.model, o.measurement, ErrorsLine(c.errors));
  if (!x.vib_note.empty()) fmt::print("{}\n", x.vib_note);
  PrintEsCells("vibration E_s by speed and force", x.es_cells);
  fmt::print("\nwhere the residual lives (share of each channel's residual variance):\n");
  for (std::size_t k = 0; k < x.axes.size() && k < 5; ++k)
    fmt::print("  {:9s} {:13s} {:5.1f} %  {}\n", x.axes[k].axis, ChannelName(x.axes[k].channel),
               100 * x.axes[k].share, x.axes[k].description);
  fmt::print("\nlargest systematic residuals:\n");
  for (const auto& f : x.largest)
    fmt::print("  {} by {}, {}: mean {:+.4f}, rms {:.4f} (n {})\n", f.quantity, f.dimension, f.bin,
               f.mean, f.rms, f.n);
  fmt::print("\ndetail:\n");
  for (const auto& [dim, qs] : c.breakdown)
    for (const auto& [q, rows] : qs) {
      fmt::print("\n{} by {}:\n", q, dim);
      for (const auto& row : rows)
        if (row.n)
          fmt::print("  {:28s} n {:6d}  mean {:+.4f}  rms {:.4f}\n", row.label, row.n, row.mean,
                     row.rms);
    }
  if (!x.files.empty()) fmt::print("\nplots: {} files in {}\n", x.files.size(), o.plots);
}

int RunCompare(const CompareArgs& o) {
  auto m = LoadModel(o.model);
  CompareReport x;
  x.vib_note = AttachVibration(o.model, &m);
  const auto r = Load(o.measurement, &m);
  x.c = Compare(m, r);
  x.es_cells = VibrationEsByCondition(r, Predict(m, r), Split::kAll);
  x.axes = RankResidualAxes(m, r, Predict(m, r));
  x.largest = LargestFailures(x.c, 5);
  if (!o.plots.empty()) {
    if (!o.before.empty()) {
      auto mb = LoadModel(o.before);
      AttachVibration(o.before, &mb);
      const auto cb = Compare(mb, r);
      x.files = Plots(x.c, m, r, o.plots, &cb, &mb);
    } else {
      x.files = Plots(x.c, m, r, o.plots, nullptr, nullptr);
    }
  }
  if (o.json)
    PrintCompareJson(x);
  else
    PrintCompare(o, x);
  return kExitOk;
}

}  // namespace

void AddCompare(CLI::App& app) {
  auto o = std::make_shared<CompareArgs>();
  auto* cmd = app.add_subcommand(
      "compare",
      "Replay a measurement's kinematics through a model and report its errors. It opens with a\n"
      "summary: the error per channel (normal force, tangential force, vibration E_s; a\n"
      "material's AR bank or neural model is scored by its spectrum, with E_s by speed and\n"
      "force), where the\n"
      "residual lives (share of each channel's residual variance along time, speed, load,\n"
      "direction, position, regime and band, with the shape in words) and the largest systematic\n"
      "residuals; the breakdown bin by bin follows. --plots draws the residual against each\n"
      "dimension (speed on a log axis); with --before, an earlier model's residuals are drawn on\n"
      "the same axes.");
  cmd->add_option("--model", o->model, "Model (workbench or renderer material TOML)")->required();
  cmd->add_option("--measurement", o->measurement, "Measurement CSV v1")->required();
  cmd->add_flag("--json", o->json,
                "Print {\"error\": x, \"channels\": {...}, \"summary\": {\"axes\", \"largest\"}, "
                "\"breakdown\": {...}}");
  cmd->add_option("--plots", o->plots, "Folder for residual plots (SVG and PNG)");
  cmd->add_option("--before", o->before,
                  "An earlier model whose residuals the plots show on the same axes");
  cmd->callback([o] { RunGuarded([&] { return RunCompare(*o); }); });
}

}  // namespace hapticlab::cli::workbench_cli
