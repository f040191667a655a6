// Workbench prediction: a model replayed over measured kinematics, residuals and errors.

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/modeling/workbench_vibration.hpp"
#include "workbench_internal.hpp"

namespace hapticlab::modeling::wb {

namespace internal {

double NormalForce(const std::vector<Resolved>& eff, const Replay::Sample& s) {
  if (!s.contact) return 0;
  NormalTerms t;
  for (const auto& x : eff) x.e->Normal(x.p.data(), s, t);
  const double dn = s.d_m > 0 ? std::pow(s.d_m / kMm, t.n) : 0;
  return std::max(0.0, dn * (t.K + t.B * s.ddot_mps) + t.extra_N);
}

// Friction force the surface exerts on the tool, replayed over every sample (the Dahl bristle
// has state). Exact per-sample vector bristle update, as in the renderer.
void FrictionForces(const std::vector<Resolved>& eff, const Replay& r, double* ftx, double* fty) {
  double Fx = 0, Fy = 0, ax = 0, ay = 0;  // bristle force, position seen through the play
  bool prev_contact = false;
  for (std::size_t i = 0; i < r.samples().size(); ++i) {
    const auto& s = r.samples()[i];
    if (!s.contact) {
      Fx = Fy = 0;
      ftx[i] = fty[i] = 0;
      prev_contact = false;
      continue;
    }
    // A new recording (concatenated files) starts its bristle afresh, as after lifting off.
    if (i > 0 && r.samples()[i - 1].recording != s.recording) prev_contact = false;
    FrictionTerms t;
    for (const auto& x : eff) x.e->Friction(x.p.data(), s, t);
    const double fc = std::max(0.0, s.fload_N * (t.mu_k * t.mu_scale + t.mu_add));
    if (t.kappa > 0) {
      if (!prev_contact || !(fc > 0)) {
        Fx = Fy = 0;
        ax = s.x_m, ay = s.y_m;
      } else {
        // The bristle follows the position through a play (backlash) of half-width
        // resolution / 2: noise at rest does not move it, and real motion loses only that
        // play at each reversal (not whole sub-resolution excursions, as a fixed anchor would).
        const double h = 0.5 * r.position_resolution_m;
        const double ex = s.x_m - ax, ey = s.y_m - ay, dist = std::hypot(ex, ey);
        if (dist > h) {
          const double dx = ex * (1 - h / dist), dy = ey * (1 - h / dist), len = dist - h;
          const double tx = fc * dx / len, ty = fc * dy / len, a = std::exp(-t.kappa * len / fc);
          Fx = tx + (Fx - tx) * a;
          Fy = ty + (Fy - ty) * a;
          ax += dx, ay += dy;
        }
        const double mag = std::hypot(Fx, Fy);
        if (mag > fc) Fx *= fc / mag, Fy *= fc / mag;
      }
    } else if (s.speed_mps > 0) {
      const double g = fc * std::tanh(s.speed_mps / kPreslidingSpeed_mps) / s.speed_mps;
      Fx = g * s.vx_mps;
      Fy = g * s.vy_mps;
    } else {
      Fx = Fy = 0;
    }
    ftx[i] = -(Fx + t.mu_b * s.vx_mps);
    fty[i] = -(Fy + t.mu_b * s.vy_mps);
    prev_contact = true;
  }
}

// Vibration design row: features of every vibration effect (after the intercept).
std::vector<double> VibrationRow(const std::vector<Resolved>& eff, const Replay::Window& w) {
  std::vector<double> row{1.0};
  for (const auto& x : eff) {
    const int c = x.e->VibrationColumns();
    const std::size_t at = row.size();
    row.resize(at + c);
    x.e->VibrationFeatures(x.p.data(), w, row.data() + at);
  }
  return row;
}

bool InSplit(int block, Split s) {
  return s == Split::kAll || (s == Split::kTrain) == (block % 2 == 0);
}

}  // namespace internal

using namespace internal;  // NOLINT(google-build-using-namespace): the workbench's own kernels

// ---------------------------------------------------------------------------------------------
Prediction Predict(const Model& m, const Replay& r) {
  Prediction p;
  const auto nrm = Resolve(m, r, Channel::kNormal);
  p.fn_N.resize(r.samples().size());
  for (std::size_t i = 0; i < r.samples().size(); ++i) p.fn_N[i] = NormalForce(nrm, r.samples()[i]);
  p.ftx_N.resize(r.samples().size());
  p.fty_N.resize(r.samples().size());
  FrictionForces(Resolve(m, r, Channel::kFriction), r, p.ftx_N.data(), p.fty_N.data());
  if (m.HasVibration() && r.has_vibration) {
    const auto vib = Resolve(m, r, Channel::kVibration);
    const auto& core = m.coef.at(std::string(effect::kCore));
    const std::size_t nb = r.band_lo_hz.size();
    if (core.size() != nb)
      throw InputError(
          r.file, 0, "acc_mps2",
          fmt::format("the model's vibration has {} bands, the measurement's analysis {}",
                      core.size(), nb));
    for (const auto& w : r.windows) {
      const auto row = VibrationRow(vib, w);
      std::vector<double> bp(nb);
      for (std::size_t b = 0; b < nb; ++b) {
        double lp = core[b];
        std::size_t col = 1;
        for (const auto& x : vib) {
          const int c = x.e->VibrationColumns();
          const auto it = m.coef.find(x.name);
          if (it != m.coef.end() && it->second.size() == nb * c)
            for (int j = 0; j < c; ++j) lp += it->second[b * c + j] * row[col + j];
          col += c;
        }
        if (const auto lo = m.coef.find(std::string(kCoefRangeLo));
            lo != m.coef.end() && lo->second.size() == nb)
          lp = std::clamp(lp, lo->second[b], m.coef.at(std::string(kCoefRangeHi))[b]);
        bp[b] = std::exp(lp);
      }
      p.band_power.push_back(std::move(bp));
    }
  } else if (m.vibration_model && r.has_vibration) {
    p.band_power = PredictModelBands(*m.vibration_model, r, m.vibration_spectra.get());
  }
  return p;
}

Residuals ComputeResiduals(const Model&, const Replay& r, const Prediction& p) {
  Residuals res;
  const std::size_t n = r.samples().size();
  res.normal_N.assign(n, 0);
  res.friction_N.assign(n, 0);
  res.ratio.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& s = r.samples()[i];
    if (!s.contact) continue;
    res.normal_N[i] = s.fn_N - p.fn_N[i];
    if (s.speed_mps >= kPreslidingSpeed_mps) {
      const double ux = s.vx_mps / s.speed_mps, uy = s.vy_mps / s.speed_mps;
      res.friction_N[i] = -(s.ftx_N * ux + s.fty_N * uy) + (p.ftx_N[i] * ux + p.fty_N[i] * uy);
    }
    if (s.speed_mps >= kSlidingSpeed_mps && s.fn_N > 0.05)
      res.ratio[i] = (std::hypot(s.ftx_N, s.fty_N) - std::hypot(p.ftx_N[i], p.fty_N[i])) / s.fn_N;
  }
  for (std::size_t w = 0; w < p.band_power.size(); ++w) {
    std::vector<double> lb;
    for (std::size_t b = 0; b < p.band_power[w].size(); ++b)
      lb.push_back(std::log(r.windows[w].band_power[b] / p.band_power[w][b]));
    res.log_band.push_back(std::move(lb));
  }
  return res;
}

const ChannelErrors& Errors::Of(Channel c) const {
  switch (c) {
    case Channel::kNormal:
      return normal_force;
    case Channel::kFriction:
      return friction;
    case Channel::kVibration:
      break;
  }
  return vibration;
}

std::map<Channel, double> Errors::Normalized() const {
  std::map<Channel, double> out;
  for (const Channel c : {Channel::kNormal, Channel::kFriction, Channel::kVibration})
    if (Of(c).present) out[c] = Of(c).normalized;
  return out;
}

Errors ComputeErrors(const Replay& r, const Prediction& p, Split split) {
  Errors e;
  double sn = 0, nn = 0, st = 0, nt = 0, sr = 0;
  int nr = 0;
  for (std::size_t i = 0; i < r.samples().size(); ++i) {
    const auto& s = r.samples()[i];
    if (!s.contact || !InSplit(s.block, split)) continue;
    const double en = (s.fn_N - p.fn_N[i]) * (s.fn_N - p.fn_N[i]);
    const double dx = s.ftx_N - p.ftx_N[i], dy = s.fty_N - p.fty_N[i], et = dx * dx + dy * dy;
    sn += en, nn += s.fn_N * s.fn_N;
    st += et, nt += s.ftx_N * s.ftx_N + s.fty_N * s.fty_N;
    e.normal_force.block_sse[s.block] += en;
    e.friction.block_sse[s.block] += et;
    if (s.speed_mps >= kSlidingSpeed_mps && s.fn_N > 0.05) {
      const double d = (std::hypot(s.ftx_N, s.fty_N) - std::hypot(p.ftx_N[i], p.fty_N[i])) / s.fn_N;
      sr += d * d, ++nr;
    }
  }
  int count = 0;
  if (nn > 0) {
    e.normal_force.present = true;
    e.normal_force.normalized = std::sqrt(sn / nn);
    e.normal_force.normalizer = nn;
    ++count;
  }
  if (nt > 0) {
    e.friction.present = true;
    e.friction.normalized = std::sqrt(st / nt);
    e.friction.normalizer = nt;
    ++count;
  }
  // RMS in newtons over the counted samples.
  int ns = 0;
  for (const auto& s : r.samples()) ns += s.contact && InSplit(s.block, split);
  e.normal_force_rms_N = ns ? std::sqrt(sn / ns) : 0;
  e.tangential_rms_N = ns ? std::sqrt(st / ns) : 0;
  e.friction_ratio_rms = nr ? std::sqrt(sr / nr) : 0;
  if (!p.band_power.empty()) {
    double se = 0;
    int nw = 0;
    for (std::size_t w = 0; w < r.windows.size(); ++w) {
      if (!InSplit(r.windows[w].block, split)) continue;
      const double es = WindowEs(r.windows[w].band_power, p.band_power[w]);
      se += es, ++nw;
      e.vibration.block_sse[r.windows[w].block] += es;
    }
    if (nw > 0) {
      e.vibration.present = true;
      e.vibration.normalized = se / nw;
      e.vibration.normalizer = nw;
      ++count;
    }
  }
  double sum = 0;  // in Channel order, as the reports list the channels
  for (const auto& [k, v] : e.Normalized()) sum += v;
  e.overall = count ? sum / count : 0;
  return e;
}

}  // namespace hapticlab::modeling::wb
