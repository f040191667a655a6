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

namespace {

// What the candidates are scored against: the model refitted on the training blocks, its
// prediction, held-out errors and residuals.
struct Baseline {
  Model model;
  Prediction prediction;
  Errors errors;
  Residuals residuals;
};

// The candidates: effects the model lacks whose prerequisites it has, on channels with data.
std::vector<const Effect*> Candidates(const Model& base, const Replay& r) {
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
  return cands;
}

// Paired over held-out blocks: t of the per-block log ratio of the channel's error before and
// after (scale free, so a few blocks with large errors do not dominate); 0 with under 3 blocks.
double PairedBlockT(const ChannelErrors& before, const ChannelErrors& after) {
  std::vector<double> d;
  const auto& bb = before.block_sse;
  const auto& bc = after.block_sse;
  for (const auto& [blk, v] : bb)
    if (bc.count(blk) && v > 0 && bc.at(blk) > 0) d.push_back(std::log(v / bc.at(blk)));
  if (d.size() < 3) return 0;
  const double nd = static_cast<double>(d.size());
  const double mean = std::accumulate(d.begin(), d.end(), 0.0) / nd;
  double var = 0;
  for (const double x : d) var += (x - mean) * (x - mean);
  var /= nd - 1;
  return var > 0 ? mean / std::sqrt(var / nd) : (mean > 0 ? 1e9 : 0);
}

// The candidate's channel refit's verdict into c: its summary, and why a fit that passes the
// numbers is still not support (a parameter of the effect at a bound, no convergence).
void NoteFit(const FitReport& rep, Channel channel, Candidate* c) {
  const auto* cf = rep.Find(channel);
  if (!cf) return;
  c->fit = cf->summary;
  for (const auto& p : cf->params)
    if (p.effect == c->effect && p.at_bound)
      c->rejected.push_back(
          fmt::format("its fit ended with {} at a bound ({:.4g})", p.name, p.value));
  if (!cf->summary.usable)
    c->rejected.push_back(
        fmt::format("its fit did not converge ({})", TerminationText(cf->summary)));
}

// Effect e added to the baseline, fitted on the training blocks (its channel only) and scored
// on the held-out ones; its prediction into *pred and its evidence into *note.
Candidate ScoreCandidate(const Effect& e, const Baseline& base, const Replay& r,
                         const DiagnoseOptions& o, Prediction* pred, EvidenceNote* note) {
  Model m = base.model;
  AddEffects(&m, {std::string(e.name())}, r);
  FitOptions fo{.split = Split::kTrain};
  fo.normal = e.channel() == Channel::kNormal;
  fo.friction = e.channel() == Channel::kFriction;
  fo.vibration = e.channel() == Channel::kVibration;
  const auto rep = Fit(&m, r, fo);
  *pred = Predict(m, r);
  const auto err = ComputeErrors(r, *pred, Split::kHeldOut);
  Candidate c;
  c.effect = std::string(e.name());
  c.channel = e.channel();
  NoteFit(rep, e.channel(), &c);
  c.error_after = err.overall;
  c.error_reduction = base.errors.overall - err.overall;
  const auto& e0 = base.errors.Of(e.channel());
  const auto& e1 = err.Of(e.channel());
  const double b0 = e0.present ? e0.normalized : 0;
  const double b1 = e1.present ? e1.normalized : 0;
  c.relative_reduction = b0 > 0 ? (b0 - b1) / b0 : 0;
  c.t_statistic = PairedBlockT(e0, e1);
  *note = e.Evidence(r, base.residuals);
  if (note->contradicts)
    c.rejected.push_back("its own evidence does not show the pattern it produces");
  const bool numbers = c.relative_reduction >= o.min_relative_reduction && c.t_statistic >= o.min_t;
  c.supported = numbers && c.rejected.empty();
  if (!numbers) c.rejected.clear();  // the numbers alone say no; the reasons above add nothing
  for (const auto& [name, v] : m.params[c.effect]) c.params[name] = v;
  if (c.channel == Channel::kVibration) {
    // Summarize the coefficients by their spread in dB.
    const auto& v = m.coef[c.effect];
    double mx = 0;
    for (const double x : v) mx = std::max(mx, std::abs(x));
    c.params["max_coefficient_dB"] = mx * 10 / std::log(10.0);
  }
  return c;
}

// Every candidate scored, on o.threads threads (0: one per core); out, preds and notes are
// indexed as cands.
void ScoreCandidates(const std::vector<const Effect*>& cands, const Baseline& base, const Replay& r,
                     const DiagnoseOptions& o, std::vector<Candidate>* out,
                     std::vector<Prediction>* preds, std::vector<EvidenceNote>* notes) {
  out->resize(cands.size());
  preds->resize(cands.size());
  notes->resize(cands.size());
  std::atomic<std::size_t> next{0}, done{0};
  auto work = [&] {
    for (std::size_t k; (k = next++) < cands.size();) {
      (*out)[k] = ScoreCandidate(*cands[k], base, r, o, &(*preds)[k], &(*notes)[k]);
      if (o.progress)
        o.progress((*out)[k].effect, static_cast<int>(++done), static_cast<int>(cands.size()));
    }
  };
  const int threads = o.threads > 0 ? o.threads : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
}

// A candidate's change to the prediction on the held-out data: ln band-power ratios for
// vibration, force differences in contact for the force channels.
std::vector<double> PredictionChange(const Replay& r, Channel channel, const Prediction& p,
                                     const Prediction& pbase) {
  std::vector<double> v;
  if (channel == Channel::kVibration) {
    for (std::size_t w = 0; w < r.windows.size(); ++w)
      if (r.windows[w].block % 2)
        for (std::size_t b = 0; b < p.band_power[w].size(); ++b)
          v.push_back(std::log(p.band_power[w][b] / pbase.band_power[w][b]));
    return v;
  }
  for (std::size_t i = 0; i < r.samples().size(); ++i) {
    if (!r.samples()[i].contact || r.samples()[i].block % 2 == 0) continue;
    if (channel == Channel::kNormal) {
      v.push_back(p.fn_N[i] - pbase.fn_N[i]);
    } else {
      v.push_back(p.ftx_N[i] - pbase.ftx_N[i]);
      v.push_back(p.fty_N[i] - pbase.fty_N[i]);
    }
  }
  return v;
}

// Confounding: supported candidates of one channel whose changes to the held-out prediction
// are strongly correlated (> 0.8) explain the same residual.
void MarkConfounded(const Replay& r, const std::vector<Prediction>& preds, const Prediction& pbase,
                    std::vector<Candidate>* out) {
  auto& c = *out;
  for (std::size_t a = 0; a < c.size(); ++a)
    for (std::size_t b = a + 1; b < c.size(); ++b) {
      if (!c[a].supported || !c[b].supported || c[a].channel != c[b].channel) continue;
      const auto va = PredictionChange(r, c[a].channel, preds[a], pbase),
                 vb = PredictionChange(r, c[b].channel, preds[b], pbase);
      double saa = 0, sbb = 0, sab = 0;
      for (std::size_t i = 0; i < va.size(); ++i)
        saa += va[i] * va[i], sbb += vb[i] * vb[i], sab += va[i] * vb[i];
      if (saa > 0 && sbb > 0 && sab / std::sqrt(saa * sbb) > 0.8) {
        c[a].confounded_with.push_back(c[b].effect);
        c[b].confounded_with.push_back(c[a].effect);
      }
    }
}

// The evidence sentence: the measured pattern always; its cause only for a supported effect.
std::string EvidenceOf(const Candidate& c, const EvidenceNote& note) {
  if (!c.supported)
    return fmt::format(
        "not supported: held-out {} error {} by {:.1f} % (paired t = {:.1f}){}; residual "
        "pattern: {}",
        ChannelName(c.channel), c.relative_reduction >= 0 ? "falls" : "rises",
        std::abs(c.relative_reduction) * 100, c.t_statistic,
        c.rejected.empty() ? "" : fmt::format(", but {}", fmt::join(c.rejected, "; ")),
        note.pattern);
  std::string s = note.Sentence(true);
  if (!c.confounded_with.empty())
    s += fmt::format(
        " (confounded with {}: they explain the same residual; measure the regime that "
        "separates them)",
        fmt::join(c.confounded_with, ", "));
  return s;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
Diagnosis Diagnose(const Model& m0, const Replay& r, const DiagnoseOptions& o) {
  Diagnosis dx;
  Baseline base{m0, {}, {}, {}};
  if (!base.model.params.count(std::string(effect::kCore))) AddEffects(&base.model, {}, r);
  Fit(&base.model, r, {.split = Split::kTrain});
  base.prediction = Predict(base.model, r);
  base.errors = ComputeErrors(r, base.prediction, Split::kHeldOut);
  base.residuals = ComputeResiduals(base.model, r, base.prediction);
  dx.baseline_error = base.errors.overall;
  dx.baseline_channel = base.errors.Normalized();
  dx.vibration_by_condition = VibrationEsByCondition(r, base.prediction, Split::kHeldOut);

  std::vector<Candidate> out;
  std::vector<Prediction> preds;
  std::vector<EvidenceNote> notes;
  ScoreCandidates(Candidates(base.model, r), base, r, o, &out, &preds, &notes);
  MarkConfounded(r, preds, base.prediction, &out);
  for (std::size_t k = 0; k < out.size(); ++k) out[k].evidence = EvidenceOf(out[k], notes[k]);
  std::stable_sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) {
    return a.error_reduction > b.error_reduction;
  });
  dx.candidates = std::move(out);

  // What no candidate explains.
  bool any_supported = false;
  for (const auto& c : dx.candidates) any_supported = any_supported || c.supported;
  dx.unexplained = ExplainResidual(base.model, r, base.prediction, base.errors, any_supported,
                                   o.unexplained_ratio);
  return dx;
}

}  // namespace hapticlab::modeling::wb
