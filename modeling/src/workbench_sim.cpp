// Ground-truth simulator for the workbench: human-like strokes on a sample whose physics has a
// chosen set of effects, written as a measurement with sensor noise. Deliberately a separate
// implementation from the workbench's effect code (bristles integrated by explicit Euler
// substeps, the normal law inverted for a commanded load, vibration from a resonance at the
// surface's spatial frequency) so the hidden-effect tests do not test the model against itself.

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/sim_truth/friction.hpp"

namespace hapticlab::modeling::wb {

bool TruthParams::Has(std::string_view e) const {
  return std::find(effects.begin(), effects.end(), e) != effects.end();
}

namespace {

constexpr double kPi = std::numbers::pi;

// Static part of the normal law: load at penetration d.
double StaticLoad(const TruthParams& t, double d) {
  if (d <= 0) return 0;
  const double n = t.Has(effect::kHcExponent) ? t.n : 1.0;
  double f = t.K1mm_N * std::pow(d / 1e-3, n);
  if (t.Has(effect::kBaseLayer) && d > t.layer_m) f += t.base_K_N_per_m * (d - t.layer_m);
  return f;
}

double InvertLoad(const TruthParams& t, double load) {
  if (load <= 0) return load / (t.K1mm_N / 1e-3);  // above the surface, out of contact
  double lo = 0, hi = 0.02;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (StaticLoad(t, mid) < load ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

SimulatedMeasurement Simulate(const TruthParams& tp) {
  TruthParams t = tp;
  if (t.effects.empty()) t.effects = BaselineEffects();
  Rng rng(t.seed);
  const double fs = t.rate_hz, dt = 1 / fs;
  const std::size_t N = static_cast<std::size_t>(t.duration_s * fs);
  const double half = t.area_m / 2;

  // 1. Kinematics in the plane and the commanded load, segment by segment.
  std::vector<double> x(N), y(N), load(N);
  std::size_t i = 0;
  double px = 0, py = 0, prev_dir = 0;
  bool have_prev = false;
  while (i < N) {
    const bool slow = rng.Uniform() < 0.2;
    const double vp = slow ? std::exp(rng.Uniform(std::log(0.0015), std::log(0.01)))
                           : std::exp(rng.Uniform(std::log(0.01), std::log(0.15)));
    double len = slow ? rng.Uniform(0.003, 0.008) : rng.Uniform(0.008, 0.03);
    const bool reverse = have_prev && rng.Uniform() < 0.4;
    double phi = reverse ? prev_dir + kPi : rng.Uniform(-kPi, kPi);
    for (int tries = 0; tries < 30; ++tries) {
      const double ex = px + len * std::cos(phi), ey = py + len * std::sin(phi);
      if (std::abs(ex) < half && std::abs(ey) < half) break;
      phi = tries < 20 ? rng.Uniform(-kPi, kPi) : std::atan2(-py, -px);
      if (tries >= 20) len = std::min(len, std::hypot(px, py));
    }
    prev_dir = phi;
    have_prev = true;
    const double T = 1.875 * len / vp;  // minimum-jerk: peak speed 1.875 L / T
    const double L0 = std::exp(rng.Uniform(std::log(0.3), std::log(2.5)));
    const double fl = rng.Uniform(1, 3), ph = rng.Uniform(0, 2 * kPi);
    const std::size_t n = std::max<std::size_t>(2, static_cast<std::size_t>(T * fs));
    for (std::size_t k = 0; k < n && i < N; ++k, ++i) {
      const double tau = static_cast<double>(k) / static_cast<double>(n),
                   s = len * (10 * std::pow(tau, 3) - 15 * std::pow(tau, 4) + 6 * std::pow(tau, 5));
      x[i] = px + s * std::cos(phi);
      y[i] = py + s * std::sin(phi);
      load[i] = L0 * (1 + 0.2 * std::sin(2 * kPi * fl * static_cast<double>(k) * dt + ph));
    }
    px += len * std::cos(phi);
    py += len * std::sin(phi);
    // Dwell at rest, pressing a little (pre-sliding and normal dynamics), sometimes lifting off.
    const double dwell = rng.Uniform(0.05, 0.2);
    const bool lift = rng.Uniform() < 0.12;
    const double L1 = lift ? -0.3 : L0;
    const std::size_t nd = static_cast<std::size_t>(dwell * fs);
    for (std::size_t k = 0; k < nd && i < N; ++k, ++i) {
      x[i] = px;
      y[i] = py;
      load[i] = L1 * (1 + 0.15 * std::sin(2 * kPi * 4 * static_cast<double>(k) * dt));
    }
  }
  // Smooth the commanded load (a hand does not step): first order, 60 ms.
  const double a = std::exp(-dt / 0.06);
  for (std::size_t k = 1; k < N; ++k) load[k] = a * load[k - 1] + (1 - a) * load[k];
  for (std::size_t k = 1; k < N; ++k) load[k] = a * load[k - 1] + (1 - a) * load[k];

  // 2. Penetration from the static law, then the full normal force with damping.
  std::vector<double> d(N), dd(N), vx(N), vy(N);
  for (std::size_t k = 0; k < N; ++k) d[k] = InvertLoad(t, load[k]);
  for (std::size_t k = 0; k < N; ++k) {
    const std::size_t k0 = k ? k - 1 : k, k1 = k + 1 < N ? k + 1 : k;
    const double h = static_cast<double>(k1 - k0) * dt;
    dd[k] = (d[k1] - d[k0]) / h;
    vx[k] = (x[k1] - x[k0]) / h;
    vy[k] = (y[k1] - y[k0]) / h;
  }
  SimulatedMeasurement out;
  out.truth = t;
  out.fn_clean.resize(N);
  out.ftx_clean.resize(N);
  out.fty_clean.resize(N);
  out.acc_state.resize(N);
  const double n_exp = t.Has(effect::kHcExponent) ? t.n : 1.0;
  for (std::size_t k = 0; k < N; ++k) {
    if (d[k] <= 0) continue;
    const double dn = std::pow(d[k] / 1e-3, n_exp);
    const double K = t.K1mm_N * (1 + t.K_position_amp * x[k] / half);
    double f = dn * (K + (t.Has(effect::kHcDamping) ? t.B1mm_Ns_per_m * dd[k] : 0.0));
    if (t.Has(effect::kBaseLayer) && d[k] > t.layer_m) f += t.base_K_N_per_m * (d[k] - t.layer_m);
    out.fn_clean[k] = std::max(0.0, f);
  }

  // 3. Friction: Dahl bristle by explicit Euler over 20 substeps of each sample's displacement.
  // Direction of motion: of the last motion faster than 1 mm/s (undefined at rest otherwise).
  std::vector<double> dirs(N);
  for (std::size_t k = 0; k < N; ++k)
    dirs[k] = std::hypot(vx[k], vy[k]) > 1e-3 ? std::atan2(vy[k], vx[k]) : (k ? dirs[k - 1] : 0.0);
  double Fx = 0, Fy = 0;
  for (std::size_t k = 0; k < N; ++k) {
    const double fn = out.fn_clean[k];
    if (fn <= 0) {
      Fx = Fy = 0;
      continue;
    }
    const double v = std::hypot(vx[k], vy[k]), dir = dirs[k];
    double S = 1 + t.mu_drift * (static_cast<double>(k) / static_cast<double>(N) - 0.5);
    if (t.Has(effect::kAnisotropicFriction))
      S *= 1 + t.aniso[0] * std::cos(dir) + t.aniso[1] * std::sin(dir) +
           t.aniso[2] * std::cos(2 * dir) + t.aniso[3] * std::sin(2 * dir);
    if (t.Has(effect::kLoadDependentFriction)) S *= std::pow(fn, t.load_alpha - 1);
    if (t.Has(effect::kPositionDependentFriction)) {
      const double u = x[k] / half, w = y[k] / half;
      S *= 1 + t.tile_amp * (0.8 * u - 0.5 * w + 0.6 * u * w - 0.4 * (1.5 * u * u - 0.5));
    }
    const sim_truth::StribeckFriction law{.mu_k = t.Has(effect::kCoulomb) ? t.mu_k * S : 0.0,
                                          .dmu_s = t.Has(effect::kStribeck) ? t.stribeck_dmu : 0.0,
                                          .stribeck_speed_mps = t.stribeck_vs_mps};
    const double mu = law.Mu(v);
    const double fc = fn * mu;
    if (fc > 0 && t.Has(effect::kDahl)) {
      if (k == 0 || out.fn_clean[k - 1] <= 0) {
        Fx = Fy = 0;
      } else {
        const double sx = (x[k] - x[k - 1]) / 20, sy = (y[k] - y[k - 1]) / 20,
                     sl = std::hypot(sx, sy);
        for (int j = 0; j < 20; ++j) {
          Fx += t.kappa_N_per_m * (sx - sl * Fx / fc);
          Fy += t.kappa_N_per_m * (sy - sl * Fy / fc);
        }
        const double mag = std::hypot(Fx, Fy);
        if (mag > fc) Fx *= fc / mag, Fy *= fc / mag;
      }
    } else if (fc > 0 && v > 0) {
      const double g = fc * std::tanh(v / 0.5e-3) / v;
      Fx = g * vx[k];
      Fy = g * vy[k];
    } else {
      Fx = Fy = 0;  // no friction level, or at rest without pre-sliding
    }
    const double mub = t.Has(effect::kViscous) ? t.mu_b_Ns_per_m : 0.0;
    out.ftx_clean[k] = -(Fx + mub * vx[k]);
    out.fty_clean[k] = -(Fy + mub * vy[k]);
  }

  // 4. Vibration: AR(2) resonance at v / lambda excited in proportion to speed, load and
  // direction factors; sensor noise on top.
  std::vector<double> acc(N);

  const double r = 0.85;
  for (std::size_t k = 0; k < N; ++k) {
    const double fn = out.fn_clean[k], v = std::hypot(vx[k], vy[k]);
    const double fr =
        t.Has(effect::kVibrationSpeed) ? std::clamp(v / t.wavelength_m, 30.0, 0.4 * fs) : 200.0;
    const double a1 = 2 * r * std::cos(2 * kPi * fr / fs), a2 = -r * r;
    double pw = 0;
    if (fn > 0 && v > 1e-3) {
      pw = t.vib_sigma * t.vib_sigma;
      if (t.Has(effect::kVibrationSpeed)) pw *= std::pow(v / 0.05, 2 * t.vib_speed_exp);
      if (t.Has(effect::kVibrationForce)) pw *= std::pow(fn, 2 * t.vib_force_exp);
      if (t.Has(effect::kVibrationDirection))
        pw *= std::exp(t.vib_dir_amp * std::cos(2 * (dirs[k] - 0.3)));
      pw *= (1 - r);
    }
    const double prev1 = k ? acc[k - 1] : 0, prev2 = k > 1 ? acc[k - 2] : 0;
    acc[k] = a1 * prev1 + a2 * prev2 + std::sqrt(pw) * rng.Normal();
    out.acc_state[k] = {pw, a1, a2, t.acc_noise * t.acc_noise};
  }

  // 5. The measurement, with sensor noise.
  auto& m = out.m;
  m.file = fmt::format("simulated(seed {})", t.seed);
  m.material = "simulated";
  m.metadata["generator"] = "hapticlab workbench ground truth";
  m.metadata["effects"] = fmt::format("{}", fmt::join(t.effects, " "));
  m.metadata["seed"] = std::to_string(t.seed);
  m.has_acceleration = true;
  m.rows.resize(N);
  m.row_lines.resize(N);
  for (std::size_t k = 0; k < N; ++k) {
    auto& row = m.rows[k];
    row.t_s = static_cast<double>(k) * dt;
    row.p_m = {x[k] + t.pos_noise_m * rng.Normal(), y[k] + t.pos_noise_m * rng.Normal(),
               -d[k] + t.pos_noise_m * rng.Normal()};
    row.v_mps = {vx[k] + t.vel_noise_mps * rng.Normal(), vy[k] + t.vel_noise_mps * rng.Normal(),
                 -dd[k] + t.vel_noise_mps * rng.Normal()};
    row.f_N = {out.ftx_clean[k] + t.force_noise_N * rng.Normal(),
               out.fty_clean[k] + t.force_noise_N * rng.Normal(),
               out.fn_clean[k] + t.force_noise_N * rng.Normal()};
    row.acc_mps2 = acc[k] + t.acc_noise * rng.Normal();
    m.row_lines[k] = static_cast<int>(k) + 1;
  }
  return out;
}

namespace {
// Expected band powers of every window (analytic AR(2) spectrum, Hann-weighted over the window).
std::vector<std::vector<double>> ExpectedBandPower(const SimulatedMeasurement& sim,
                                                   const Replay& r) {
  std::vector<std::vector<double>> out;
  if (r.has_vibration) {
    const double fs = r.acc_rate_hz;
    for (const auto& w : r.windows) {
      const int n = w.rows;
      std::vector<double> win(n);
      double wss = 0;
      for (int k = 0; k < n; ++k)
        win[k] = 0.5 - 0.5 * std::cos(2 * kPi * k / n), wss += win[k] * win[k];
      std::vector<double> bp;
      for (std::size_t b = 0; b < r.band_lo_hz.size(); ++b) {
        std::vector<int> bins;
        for (int k = 1; k < n / 2; ++k)
          if (k * fs / n >= r.band_lo_hz[b] && k * fs / n < r.band_hi_hz[b]) bins.push_back(k);
        if (bins.empty())
          bins.push_back(std::clamp(
              static_cast<int>(std::lround(std::sqrt(r.band_lo_hz[b] * r.band_hi_hz[b]) * n / fs)),
              1, n / 2 - 1));
        double acc = 0;
        for (const int kb : bins) {
          const double om = 2 * kPi * kb / n;
          const std::complex<double> z1 = std::polar(1.0, -om), z2 = std::polar(1.0, -2 * om);
          double s = 0;
          for (int k = 0; k < n; ++k) {
            const auto& st = sim.acc_state[w.row0 + k];
            s += win[k] * win[k] * (st[0] / std::norm(1.0 - st[1] * z1 - st[2] * z2) + st[3]);
          }
          acc += s / wss;
        }
        bp.push_back(acc / static_cast<double>(bins.size()));
      }
      out.push_back(std::move(bp));
    }
  }
  return out;
}
}  // namespace

Model TruthModel(const SimulatedMeasurement& sim, const Replay& r) {
  const auto& t = sim.truth;
  Model m;
  std::vector<std::string> force_effects;
  for (const auto& e : t.effects)
    if (FindEffect(e) && FindEffect(e)->channel() != Channel::kVibration)
      force_effects.push_back(e);
  AddEffects(&m, force_effects, r);
  const ContactParameters cp{.K1mm_N = t.K1mm_N,
                             .n = t.Has(effect::kHcExponent) ? t.n : 1.0,
                             .B1mm_Ns_per_m = t.B1mm_Ns_per_m,
                             .mu_k = t.mu_k,
                             .mu_b_Ns_per_m = t.mu_b_Ns_per_m,
                             .kappa_N_per_m = t.kappa_N_per_m};
  cp.ToModel(&m);
  m.Set(key::kBaseK_N_per_m, t.base_K_N_per_m);
  m.Set(key::kLayer_m, t.layer_m);
  m.Set(key::kStribeckDmu, t.stribeck_dmu);
  m.Set(key::kStribeckSpeed_mps, t.stribeck_vs_mps);
  for (int k = 0; k < 4; ++k) m.Set(key::kAnisotropy[k], t.aniso[k]);
  m.Set(key::kLoadAlpha, t.load_alpha);
  if (t.Has(effect::kPositionDependentFriction)) {
    // The truth's field is a quadratic in x, y: re-expand it exactly on the replay's box by
    // least squares on a grid.
    const double half = t.area_m / 2;
    const double x0 = m.Get(key::kTileX0_m, 0), x1 = m.Get(key::kTileX1_m, 0),
                 y0 = m.Get(key::kTileY0_m, 0), y1 = m.Get(key::kTileY1_m, 0);
    auto& pp = m.params[std::string(effect::kPositionDependentFriction)];
    Eigen::MatrixXd A(121, 8);
    Eigen::VectorXd b(121);
    int row = 0;
    for (int i = 0; i <= 10; ++i)
      for (int j = 0; j <= 10; ++j, ++row) {
        const double us = -1 + i / 5.0, vs = -1 + j / 5.0;
        const double x = x0 + (us + 1) / 2 * (x1 - x0), y = y0 + (vs + 1) / 2 * (y1 - y0);
        const double u = x / half, w = y / half;
        b(row) = t.tile_amp * (0.8 * u - 0.5 * w + 0.6 * u * w - 0.4 * (1.5 * u * u - 0.5));
        const double cu[3] = {1, us, 1.5 * us * us - 0.5}, cv[3] = {1, vs, 1.5 * vs * vs - 0.5};
        int c = 0;
        for (int jj = 0; jj <= 2; ++jj)
          for (int kk = 0; kk <= 2; ++kk)
            if (jj || kk) A(row, c++) = cu[jj] * cv[kk];
      }
    const Eigen::VectorXd g = A.colPivHouseholderQr().solve(b);
    int c = 0;
    for (int jj = 0; jj <= 2; ++jj)
      for (int kk = 0; kk <= 2; ++kk)
        if (jj || kk) pp[fmt::format("{}{}{}", kLegendrePrefix, jj, kk)] = g(c++);
  }
  for (auto it = m.params.begin(); it != m.params.end();)
    it = (it->first == effect::kCore || m.Has(it->first)) ? std::next(it) : m.params.erase(it);
  return m;
}

Errors NoiseFloor(const SimulatedMeasurement& sim, const Replay& r, Split split) {
  auto p = Predict(TruthModel(sim, r), r);
  p.band_power = ExpectedBandPower(sim, r);
  return ComputeErrors(r, p, split);
}

Errors CleanSignalErrors(const SimulatedMeasurement& sim, const Replay& r, Split split) {
  Prediction p;
  for (const auto& s : r.samples()) {
    p.fn_N.push_back(sim.fn_clean[s.row]);
    p.ftx_N.push_back(sim.ftx_clean[s.row]);
    p.fty_N.push_back(sim.fty_clean[s.row]);
  }
  p.band_power = ExpectedBandPower(sim, r);
  return ComputeErrors(r, p, split);
}

}  // namespace hapticlab::modeling::wb
