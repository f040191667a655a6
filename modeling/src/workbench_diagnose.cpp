// The workbench's `diagnose`: candidate effects fitted on the training blocks and scored on the
// held-out ones (the report of what none explains is in workbench_unexplained.cpp).

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <numeric>
#include <set>
#include <thread>

#include "hapticlab/modeling/workbench.hpp"

namespace hapticlab::modeling::wb {

// ---------------------------------------------------------------------------------------------
Diagnosis Diagnose(const Model& m0, const Replay& r, const DiagnoseOptions& o) {
  Diagnosis dx;
  Model base = m0;
  if (!base.params.count(std::string(effect::kCore))) AddEffects(&base, {}, r);
  Fit(&base, r, {.split = Split::kTrain});
  const auto pbase = Predict(base, r);
  const auto ebase = ComputeErrors(r, pbase, Split::kHeldOut);
  const auto res = ComputeResiduals(base, r, pbase);
  dx.baseline_error = ebase.overall;
  dx.baseline_channel = ebase.Normalized();
  dx.vibration_by_condition = VibrationEsByCondition(r, pbase, Split::kHeldOut);

  // Candidates: effects the model lacks whose prerequisites it has, on channels with data.
  std::vector<const Effect*> cands;
  for (const auto& e : Catalogue()) {
    if (base.Has(e->name())) continue;
    bool ok = true;
    for (const auto dep : e->requires_effects()) ok = ok && base.Has(dep);
    // A fixed vibration model (an AR bank, a neural model) is scored, not refitted: the
    // catalogue's vibration effects extend the band model only.
    if (e->channel() == Channel::kVibration &&
        (!r.has_vibration || r.windows.empty() || base.vibration_model))
      ok = false;
    if (ok) cands.push_back(e.get());
  }
  std::vector<Candidate> out(cands.size());
  std::vector<Prediction> preds(cands.size());
  std::vector<EvidenceNote> notes(cands.size());
  std::atomic<std::size_t> next{0}, done{0};
  auto work = [&] {
    for (std::size_t k; (k = next++) < cands.size();) {
      const Effect* e = cands[k];
      Model m = base;
      AddEffects(&m, {std::string(e->name())}, r);
      FitOptions fo{.split = Split::kTrain};
      fo.normal = e->channel() == Channel::kNormal;
      fo.friction = e->channel() == Channel::kFriction;
      fo.vibration = e->channel() == Channel::kVibration;
      const auto rep = Fit(&m, r, fo);
      preds[k] = Predict(m, r);
      const auto err = ComputeErrors(r, preds[k], Split::kHeldOut);
      auto& c = out[k];
      c.effect = std::string(e->name());
      c.channel = ChannelName(e->channel());
      if (const auto* cf = rep.Find(e->channel())) {
        c.fit = cf->summary;
        for (const auto& p : cf->params)
          if (p.effect == c.effect && p.at_bound)
            c.rejected.push_back(
                fmt::format("its fit ended with {} at a bound ({:.4g})", p.name, p.value));
        if (!cf->summary.usable)
          c.rejected.push_back(
              fmt::format("its fit did not converge ({})", cf->summary.termination));
      }
      c.error_after = err.overall;
      c.error_reduction = ebase.overall - err.overall;
      const auto& e0 = ebase.Of(e->channel());
      const auto& e1 = err.Of(e->channel());
      const double b0 = e0.present ? e0.normalized : 0;
      const double b1 = e1.present ? e1.normalized : 0;
      c.relative_reduction = b0 > 0 ? (b0 - b1) / b0 : 0;
      // Paired over held-out blocks: t of the per-block log ratio of the channel's error (scale
      // free, so a few blocks with large errors do not dominate).
      std::vector<double> d;
      const auto& bb = e0.block_sse;
      const auto& bc = e1.block_sse;
      for (const auto& [blk, v] : bb)
        if (bc.count(blk) && v > 0 && bc.at(blk) > 0) d.push_back(std::log(v / bc.at(blk)));
      if (d.size() >= 3) {
        const double nd = static_cast<double>(d.size());
        const double mean = std::accumulate(d.begin(), d.end(), 0.0) / nd;
        double var = 0;
        for (const double x : d) var += (x - mean) * (x - mean);
        var /= nd - 1;
        c.t_statistic = var > 0 ? mean / std::sqrt(var / nd) : (mean > 0 ? 1e9 : 0);
      }
      notes[k] = e->Evidence(r, res);
      if (notes[k].contradicts)
        c.rejected.push_back("its own evidence does not show the pattern it produces");
      const bool numbers =
          c.relative_reduction >= o.min_relative_reduction && c.t_statistic >= o.min_t;
      c.supported = numbers && c.rejected.empty();
      if (!numbers) c.rejected.clear();  // the numbers alone say no; the reasons above add nothing
      for (const auto& [name, v] : m.params[c.effect]) c.params[name] = v;
      if (c.channel == "vibration") {
        // Summarize the coefficients by their spread in dB.
        const auto& v = m.coef[c.effect];
        double mx = 0;
        for (const double x : v) mx = std::max(mx, std::abs(x));
        c.params["max_coefficient_dB"] = mx * 10 / std::log(10.0);
      }
      if (o.progress)
        o.progress(c.effect, static_cast<int>(++done), static_cast<int>(cands.size()));
    }
  };
  const int threads = o.threads > 0 ? o.threads : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();

  // Confounding: supported candidates of one channel whose changes to the prediction on the
  // held-out data are strongly correlated explain the same residual.
  auto change = [&](std::size_t k) {
    std::vector<double> v;
    if (out[k].channel == "vibration") {
      for (std::size_t w = 0; w < r.windows.size(); ++w)
        if (r.windows[w].block % 2)
          for (std::size_t b = 0; b < preds[k].band_power[w].size(); ++b)
            v.push_back(std::log(preds[k].band_power[w][b] / pbase.band_power[w][b]));
    } else {
      for (std::size_t i = 0; i < r.samples().size(); ++i) {
        if (!r.samples()[i].contact || r.samples()[i].block % 2 == 0) continue;
        if (out[k].channel == "normal_force") {
          v.push_back(preds[k].fn_N[i] - pbase.fn_N[i]);
        } else {
          v.push_back(preds[k].ftx_N[i] - pbase.ftx_N[i]);
          v.push_back(preds[k].fty_N[i] - pbase.fty_N[i]);
        }
      }
    }
    return v;
  };
  for (std::size_t a = 0; a < out.size(); ++a)
    for (std::size_t b = a + 1; b < out.size(); ++b) {
      if (!out[a].supported || !out[b].supported || out[a].channel != out[b].channel) continue;
      const auto va = change(a), vb = change(b);
      double saa = 0, sbb = 0, sab = 0;
      for (std::size_t i = 0; i < va.size(); ++i)
        saa += va[i] * va[i], sbb += vb[i] * vb[i], sab += va[i] * vb[i];
      if (saa > 0 && sbb > 0 && sab / std::sqrt(saa * sbb) > 0.8) {
        out[a].confounded_with.push_back(out[b].effect);
        out[b].confounded_with.push_back(out[a].effect);
      }
    }
  // Evidence: the measured pattern always; its cause only for a supported effect.
  for (std::size_t k = 0; k < out.size(); ++k) {
    auto& c = out[k];
    if (!c.supported) {
      c.evidence = fmt::format(
          "not supported: held-out {} error {} by {:.1f} % (paired t = {:.1f}){}; residual "
          "pattern: {}",
          c.channel, c.relative_reduction >= 0 ? "falls" : "rises",
          std::abs(c.relative_reduction) * 100, c.t_statistic,
          c.rejected.empty() ? "" : fmt::format(", but {}", fmt::join(c.rejected, "; ")),
          notes[k].pattern);
    } else {
      c.evidence = notes[k].Sentence(true);
      if (!c.confounded_with.empty())
        c.evidence += fmt::format(
            " (confounded with {}: they explain the same residual; measure the regime that "
            "separates them)",
            fmt::join(c.confounded_with, ", "));
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) {
    return a.error_reduction > b.error_reduction;
  });
  dx.candidates = std::move(out);

  // What no candidate explains.
  bool any_supported = false;
  for (const auto& c : dx.candidates) any_supported = any_supported || c.supported;
  dx.unexplained = ExplainResidual(base, r, pbase, ebase, any_supported, o.unexplained_ratio);
  return dx;
}

}  // namespace hapticlab::modeling::wb
