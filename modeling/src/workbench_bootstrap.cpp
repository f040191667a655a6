// Parametric bootstrap of the friction channel through the preprocessing
// (workbench_bootstrap.hpp).

#include "hapticlab/modeling/workbench_bootstrap.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/modeling/workbench_model.hpp"
#include "hapticlab/modeling/workbench_predict.hpp"
#include "hapticlab/modeling/workbench_replay.hpp"
#include "workbench_internal.hpp"

namespace hapticlab::modeling::wb {
namespace {

// The white-noise SD of `f` from its second differences over three consecutive rows that all
// pass `use` (internal::NoiseSdFromSecondDifferences); 0 with fewer than 200.
double SecondDifferenceSd(const Measurement& m, const std::function<bool(std::size_t)>& use,
                          const std::function<double(const MeasurementRow&)>& f) {
  std::vector<double> d2;
  for (std::size_t i = 1; i + 1 < m.rows.size(); ++i)
    if (use(i - 1) && use(i) && use(i + 1))
      d2.push_back(f(m.rows[i - 1]) - 2 * f(m.rows[i]) + f(m.rows[i + 1]));
  return d2.size() < 200 ? 0 : internal::NoiseSdFromSecondDifferences(std::move(d2));
}

// The truth the copies are simulated from (the parametric bootstrap simulates from the fitted
// model as it is, its bristle's play included): the recording's own path and load as the replay
// smooths them, at every row (the recording's rate, not the fit's decimated one), the velocity
// their central difference. Measured (docs/modeling-geometry-contact.md): without the play in
// the simulation the copies' fits were biased by +1.6 to +3.6 % in mu_b even without noise, a
// bias the recording's fit has not. `m` without its acceleration: PrepareReplay then skips the
// vibration windows (FFTs).
Replay TruthPath(const Measurement& m, const ReplayOptions& replay) {
  ReplayOptions every_row = replay;
  every_row.max_force_rate_hz = 1e12;
  Replay truth = PrepareReplay(m, every_row);
  auto& ts = truth.mutable_samples();
  for (std::size_t i = 0; i < ts.size(); ++i) {
    const std::size_t a = i ? i - 1 : i, b = i + 1 < ts.size() ? i + 1 : i;
    const double dt = ts[b].t_s - ts[a].t_s;
    if (!(dt > 0)) continue;
    ts[i].vx_mps = (ts[b].x_m - ts[a].x_m) / dt;
    ts[i].vy_mps = (ts[b].y_m - ts[a].y_m) / dt;
    ts[i].speed_mps = std::hypot(ts[i].vx_mps, ts[i].vy_mps);
  }
  return truth;
}

// One simulated copy into *copy: the rows in contact are the truth's path, velocity, fitted
// friction and load plus the measured noise; out of contact the rows stay as measured.
void SimulateCopy(const Measurement& m, const Replay& truth, const Prediction& force,
                  const MeasurementNoise& nz, Rng* rng, Measurement* copy) {
  const auto& ts = truth.samples();
  for (std::size_t i = 0; i < m.rows.size(); ++i) {
    const auto& s = ts[i];
    auto& row = copy->rows[i];
    row = m.rows[i];
    if (!s.contact) continue;
    row.p_m.x() = s.x_m + rng->Normal(0, nz.position_m);
    row.p_m.y() = s.y_m + rng->Normal(0, nz.position_m);
    row.v_mps.x() = s.vx_mps + rng->Normal(0, nz.velocity_mps);
    row.v_mps.y() = s.vy_mps + rng->Normal(0, nz.velocity_mps);
    row.f_N.x() = force.ftx_N[i] + rng->Normal(0, nz.tangential_N);
    row.f_N.y() = force.fty_N[i] + rng->Normal(0, nz.tangential_N);
    row.f_N.z() = s.fload_N + rng->Normal(0, nz.load_N);
  }
}

// The friction parameters refitted on o.replicates copies simulated from `model` along `truth`
// (est[k]: parameter k's fits), each fit starting from the model the copies were simulated
// from. Counts out->replicates; false with out->why_not where a copy's fit is not usable.
bool RefitCopies(const Model& model, const Measurement& m, const Replay& truth,
                 const ReplayOptions& replay, const FitOptions& fit, std::size_t np,
                 const BootstrapOptions& o, Measurement* copy, BootstrapReport* out,
                 std::vector<std::vector<double>>* est) {
  const auto force = Predict(model, truth);
  FitOptions fo = fit;
  fo.normal = fo.vibration = false;
  fo.friction = true;
  fo.uncertainty = false;
  fo.algorithm1_init = false;  // start from the model the copies were simulated from
  Rng rng(o.seed);
  est->assign(np, {});
  for (int b = 0; b < o.replicates; ++b) {
    SimulateCopy(m, truth, force, out->noise, &rng, copy);
    Model refit = model;
    const auto report = Fit(&refit, PrepareReplay(*copy, replay), fo);
    const auto* cf = report.Find(Channel::kFriction);
    ++out->replicates;
    if (cf == nullptr || !cf->summary.usable || cf->params.size() != np) {
      out->why_not = fmt::format("the fit of simulated copy {} was not usable: {}", b + 1,
                                 cf ? TerminationText(cf->summary) : "no friction channel");
      return false;
    }
    for (std::size_t k = 0; k < np; ++k) (*est)[k].push_back(cf->params[k].value);
  }
  return true;
}

// One parameter's bias and spread over the copies' fits `est` (B of them) and its corrected
// value. The correction stays in the physical range (mu_b >= 0, kappa > 0, ...): a bias larger
// than the fit's distance to its bound puts the estimate at the bound, and says so.
BootstrapParam CorrectedParam(const ParamEstimate& pe, const std::vector<double>& est, double B) {
  BootstrapParam p;
  p.effect = pe.effect;
  p.name = pe.name;
  p.fit = pe.value;
  double mean = 0, ss = 0;
  for (const double e : est) mean += e / B;
  for (const double e : est) ss += (e - mean) * (e - mean);
  p.bias = mean - pe.value;
  const double raw = pe.value - p.bias;
  p.corrected = std::clamp(raw, pe.bound_lo, pe.bound_hi);
  p.clamped = p.corrected != raw;
  p.jackknife_sd = pe.sd;
  p.bootstrap_sd = std::sqrt(ss / (B - 1));
  p.sd = std::sqrt(std::max(pe.sd * pe.sd, p.bootstrap_sd * p.bootstrap_sd) +
                   p.bootstrap_sd * p.bootstrap_sd / B);
  return p;
}

// The corrected value and SD into the fit's estimate pe (its interval with the fit's own t
// quantile; one-sided at a bound: from the bound, as far as the spread reaches) and the model.
void ApplyCorrection(const BootstrapParam& p, ParamEstimate* pe, FitSummary* summary,
                     Model* model) {
  const double t = pe->sd > 0 ? (pe->hi95 - pe->value) / pe->sd : 1.96;  // the fit's t quantile
  pe->value = p.corrected;
  pe->sd = p.sd;
  pe->lo95 = std::max(pe->value - t * pe->sd, pe->bound_lo);
  pe->hi95 = std::min(pe->value + t * pe->sd, pe->bound_hi);
  if (p.clamped) {
    pe->at_bound = true;
    summary->at_bounds.push_back(fmt::format(
        "{}.{} at its {} bound ({:.6g}) after the bootstrap's bias correction ({:.6g} - {:+.3g})",
        pe->effect, pe->name, pe->value == pe->bound_lo ? "lower" : "upper", pe->value, p.fit,
        p.bias));
  }
  model->params[pe->effect][pe->name] = p.corrected;
}

}  // namespace

MeasurementNoise EstimateNoise(const Measurement& m, double contact_force_N) {
  const auto contact = [&](std::size_t i) { return m.rows[i].f_N.z() > contact_force_N; };
  // Positions from rows at rest (a moving hand's own second difference at 1 kHz is of the order
  // of the noise); the others over every row in contact.
  const auto rest = [&](std::size_t i) {
    return contact(i) && m.rows[i].v_mps.head<2>().norm() < 1e-3;
  };
  MeasurementNoise n;
  n.position_m = std::hypot(SecondDifferenceSd(m, rest, [](auto& r) { return r.p_m.x(); }),
                            SecondDifferenceSd(m, rest, [](auto& r) { return r.p_m.y(); })) /
                 std::sqrt(2.0);
  n.velocity_mps = std::hypot(SecondDifferenceSd(m, contact, [](auto& r) { return r.v_mps.x(); }),
                              SecondDifferenceSd(m, contact, [](auto& r) { return r.v_mps.y(); })) /
                   std::sqrt(2.0);
  n.tangential_N = std::hypot(SecondDifferenceSd(m, contact, [](auto& r) { return r.f_N.x(); }),
                              SecondDifferenceSd(m, contact, [](auto& r) { return r.f_N.y(); })) /
                   std::sqrt(2.0);
  n.load_N = SecondDifferenceSd(m, contact, [](auto& r) { return r.f_N.z(); });
  return n;
}

BootstrapReport BootstrapFriction(Model* model, const Measurement& m, const ReplayOptions& replay,
                                  const FitOptions& fit, ChannelFit* friction,
                                  const BootstrapOptions& o) {
  BootstrapReport out;
  out.noise = EstimateNoise(m, replay.contact_force_N);
  if (!(out.noise.load_N > 0 && out.noise.tangential_N > 0)) {
    out.why_not = "no force noise measurable (fewer than 200 consecutive rows in contact)";
    return out;
  }
  if (friction->params.empty() || o.replicates < 2) {
    out.why_not = "no friction parameter fitted, or fewer than two replicates asked for";
    return out;
  }
  Measurement copy = m;  // friction only: no acceleration, no vibration windows
  copy.has_acceleration = false;
  const Replay truth = TruthPath(copy, replay);
  if (truth.samples().size() != m.rows.size()) {
    out.why_not = "the replay at the full rate does not have one sample per row";
    return out;
  }
  const std::size_t np = friction->params.size();
  std::vector<std::vector<double>> est;
  if (!RefitCopies(*model, m, truth, replay, fit, np, o, &copy, &out, &est)) return out;
  const auto B = static_cast<double>(o.replicates);
  for (std::size_t k = 0; k < np; ++k)
    out.params.push_back(CorrectedParam(friction->params[k], est[k], B));
  for (std::size_t k = 0; k < np; ++k)
    ApplyCorrection(out.params[k], &friction->params[k], &friction->summary, model);
  out.applied = true;
  const auto& nz = out.noise;
  out.method = fmt::format(
      "parametric bootstrap through the preprocessing ({} copies of the recording simulated from "
      "the fit along its own smoothed path and load with its measured noise: positions {:.2g} um, "
      "velocities {:.2g} mm/s, tangential forces {:.2g} mN, load {:.2g} mN): bias-corrected, "
      "SE the larger of the jackknife's and the copies' spread",
      out.replicates, 1e6 * nz.position_m, 1e3 * nz.velocity_mps, 1e3 * nz.tangential_N,
      1e3 * nz.load_N);
  return out;
}

}  // namespace hapticlab::modeling::wb
