// Ground-truth simulator for the workbench: human-like strokes on a sample whose physics has a
// chosen set of effects, written as a measurement with sensor noise. Deliberately a separate
// implementation from the workbench's model (bristles integrated by explicit Euler substeps,
// the normal law inverted for a commanded load, vibration from a resonance at the surface's
// spatial frequency; each effect's own truth hook, Effect::TruthNormal/TruthFriction/
// TruthVibration, written apart from its model hooks) so the hidden-effect tests do not test
// the model against itself.

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <optional>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/sim_truth/friction.hpp"

namespace hapticlab::modeling::wb {

bool TruthParams::Has(std::string_view e) const {
  return std::find(effects.begin(), effects.end(), e) != effects.end();
}

void TruthParams::Set(ParamKey k, double value) {
  params[std::string(k.effect)][std::string(k.name)] = value;
}

namespace {

// The spec of truth parameter `k`, or none when its effect does not declare it.
std::optional<ParamSpec> FindTruthSpec(ParamKey k) {
  const Effect* e = FindEffect(k.effect);
  HL_REQUIRE(e != nullptr, fmt::format("the truth names an unknown effect '{}'", k.effect));
  for (auto& s : e->TruthSpecs())
    if (s.name == k.name) return s;
  return std::nullopt;
}

}  // namespace

double TruthParams::Get(ParamKey k) const {
  const auto it = params.find(std::string(k.effect));
  if (it != params.end()) {
    const auto jt = it->second.find(std::string(k.name));
    if (jt != it->second.end()) return jt->second;
  }
  const auto spec = FindTruthSpec(k);
  HL_REQUIRE(spec.has_value(),
             fmt::format("the truth of {} has no parameter {}", k.effect, k.name));
  return spec->init;
}

void Effect::TruthToModel(const double* p, double /*half_side_m*/, Model* m) const {
  const auto it = m->params.find(std::string(name()));
  if (it == m->params.end()) return;
  const auto specs = TruthSpecs();
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const auto jt = it->second.find(specs[i].name);
    if (jt != it->second.end()) jt->second = p[i];
  }
}

namespace {

constexpr double kPi = std::numbers::pi;

// The values of an effect's truth parameters, in TruthSpecs order.
std::vector<double> TruthValues(const TruthParams& t, const Effect& e) {
  std::vector<double> p;
  for (const auto& s : e.TruthSpecs()) p.push_back(t.Get({e.name(), s.name}));
  return p;
}

// A truth's effects (catalogue order) with their parameter values, by channel.
struct TruthEffects {
  struct Active {
    const Effect* effect = nullptr;
    std::vector<double> p;
  };
  std::vector<Active> normal, friction, vibration;

  NormalTerms Normal(const TruthSample& s) const {
    NormalTerms n;
    for (const auto& a : normal) a.effect->TruthNormal(a.p.data(), s, n);
    return n;
  }
  TruthFrictionTerms Friction(const TruthSample& s, double mu_scale) const {
    TruthFrictionTerms f{.mu_scale = mu_scale};
    for (const auto& a : friction) a.effect->TruthFriction(a.p.data(), s, f);
    return f;
  }
  TruthVibrationTerms Vibration(const TruthSample& s, double power) const {
    TruthVibrationTerms v{.power = power};
    for (const auto& a : vibration) a.effect->TruthVibration(a.p.data(), s, v);
    return v;
  }
};

// Checks the truth (Simulate's precondition) and resolves its effects.
TruthEffects Resolve(const TruthParams& t) {
  for (const auto& e : t.effects)
    HL_REQUIRE(FindEffect(e) != nullptr, fmt::format("the truth names an unknown effect '{}'", e));
  for (const auto& [effect, values] : t.params)
    for (const auto& [name, value] : values) {
      const auto spec = FindTruthSpec({effect, name});
      HL_REQUIRE(spec.has_value() && std::isfinite(value) && spec->lo <= value && value <= spec->hi,
                 fmt::format("truth parameter {}.{} = {} is not one of the effect's or is out of "
                             "its range",
                             effect, name, value));
    }
  TruthEffects out;
  for (const auto& e : Catalogue()) {
    if (!t.Has(e->name())) continue;
    auto& list = e->channel() == Channel::kNormal     ? out.normal
                 : e->channel() == Channel::kFriction ? out.friction
                                                      : out.vibration;
    list.push_back({e.get(), TruthValues(t, *e)});
  }
  return out;
}

// Static part of the normal law: load at penetration d.
double StaticLoad(const TruthParams& t, const TruthEffects& fx, double d) {
  if (d <= 0) return 0;
  const NormalTerms n = fx.Normal({.d_m = d, .rate_hz = t.rate_hz});
  return t.K1mm_N * std::pow(d / 1e-3, n.n) + n.extra_N;
}

double InvertLoad(const TruthParams& t, const TruthEffects& fx, double load) {
  if (load <= 0) return load / (t.K1mm_N / 1e-3);  // above the surface, out of contact
  double lo = 0, hi = 0.02;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (StaticLoad(t, fx, mid) < load ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// The hand: its path in the plane and the load it commands, sample by sample.
struct Path {
  std::vector<double> x, y, load;      // [m], [m], [N]
  std::size_t i = 0;                   // samples written
  double px = 0, py = 0;               // where the last stroke ended [m]
  double prev_dir = 0, prev_load = 0;  // the last stroke's direction [rad] and load [N]
  bool have_prev = false;
};

// One minimum-jerk stroke inside the square (a reversal of the last one 40 % of the time).
void Stroke(const TruthParams& t, Rng& rng, Path& p) {
  const double fs = t.rate_hz, dt = 1 / fs, half = t.area_m / 2;
  const std::size_t N = p.x.size();
  const bool slow = rng.Uniform() < 0.2;
  const double vp = slow ? std::exp(rng.Uniform(std::log(0.0015), std::log(0.01)))
                         : std::exp(rng.Uniform(std::log(0.01), std::log(0.15)));
  double len = slow ? rng.Uniform(0.003, 0.008) : rng.Uniform(0.008, 0.03);
  const bool reverse = p.have_prev && rng.Uniform() < 0.4;
  double phi = reverse ? p.prev_dir + kPi : rng.Uniform(-kPi, kPi);
  for (int tries = 0; tries < 30; ++tries) {
    const double ex = p.px + len * std::cos(phi), ey = p.py + len * std::sin(phi);
    if (std::abs(ex) < half && std::abs(ey) < half) break;
    phi = tries < 20 ? rng.Uniform(-kPi, kPi) : std::atan2(-p.py, -p.px);
    if (tries >= 20) len = std::min(len, std::hypot(p.px, p.py));
  }
  p.prev_dir = phi;
  p.have_prev = true;
  const double T = 1.875 * len / vp;  // minimum-jerk: peak speed 1.875 L / T
  const double L0 = std::exp(rng.Uniform(std::log(0.3), std::log(2.5)));
  const double fl = rng.Uniform(1, 3), ph = rng.Uniform(0, 2 * kPi);
  const std::size_t n = std::max<std::size_t>(2, static_cast<std::size_t>(T * fs));
  for (std::size_t k = 0; k < n && p.i < N; ++k, ++p.i) {
    const double tau = static_cast<double>(k) / static_cast<double>(n),
                 s = len * (10 * std::pow(tau, 3) - 15 * std::pow(tau, 4) + 6 * std::pow(tau, 5));
    p.x[p.i] = p.px + s * std::cos(phi);
    p.y[p.i] = p.py + s * std::sin(phi);
    p.load[p.i] = L0 * (1 + 0.2 * std::sin(2 * kPi * fl * static_cast<double>(k) * dt + ph));
  }
  p.px += len * std::cos(phi);
  p.py += len * std::sin(phi);
  p.prev_load = L0;
}

// Dwell at rest, pressing a little (pre-sliding and normal dynamics), sometimes lifting off.
void Dwell(const TruthParams& t, Rng& rng, Path& p) {
  const double fs = t.rate_hz, dt = 1 / fs;
  const std::size_t N = p.x.size();
  const double dwell = rng.Uniform(0.05, 0.2);
  const bool lift = rng.Uniform() < 0.12;
  const double L1 = lift ? -0.3 : p.prev_load;
  const std::size_t nd = static_cast<std::size_t>(dwell * fs);
  for (std::size_t k = 0; k < nd && p.i < N; ++k, ++p.i) {
    p.x[p.i] = p.px;
    p.y[p.i] = p.py;
    p.load[p.i] = L1 * (1 + 0.15 * std::sin(2 * kPi * 4 * static_cast<double>(k) * dt));
  }
}

// 1. Kinematics in the plane and the commanded load, stroke by stroke.
Path Strokes(const TruthParams& t, Rng& rng) {
  const double dt = 1 / t.rate_hz;
  const std::size_t N = static_cast<std::size_t>(t.duration_s * t.rate_hz);
  Path p;
  p.x.resize(N);
  p.y.resize(N);
  p.load.resize(N);
  while (p.i < N) {
    Stroke(t, rng, p);
    Dwell(t, rng, p);
  }
  // Smooth the commanded load (a hand does not step): first order, 60 ms.
  const double a = std::exp(-dt / 0.06);
  for (std::size_t k = 1; k < N; ++k) p.load[k] = a * p.load[k - 1] + (1 - a) * p.load[k];
  for (std::size_t k = 1; k < N; ++k) p.load[k] = a * p.load[k - 1] + (1 - a) * p.load[k];
  return p;
}

// The contact's state: penetration from the static law, velocities by central differences.
struct Motion {
  std::vector<double> d, dd, vx, vy, dirs;
};

Motion Move(const TruthParams& t, const TruthEffects& fx, const Path& p) {
  const std::size_t N = p.x.size();
  const double dt = 1 / t.rate_hz;
  Motion m;
  m.d.resize(N);
  m.dd.resize(N);
  m.vx.resize(N);
  m.vy.resize(N);
  m.dirs.resize(N);
  for (std::size_t k = 0; k < N; ++k) m.d[k] = InvertLoad(t, fx, p.load[k]);
  for (std::size_t k = 0; k < N; ++k) {
    const std::size_t k0 = k ? k - 1 : k, k1 = k + 1 < N ? k + 1 : k;
    const double h = static_cast<double>(k1 - k0) * dt;
    m.dd[k] = (m.d[k1] - m.d[k0]) / h;
    m.vx[k] = (p.x[k1] - p.x[k0]) / h;
    m.vy[k] = (p.y[k1] - p.y[k0]) / h;
  }
  // Direction of motion: of the last motion faster than 1 mm/s (undefined at rest otherwise).
  for (std::size_t k = 0; k < N; ++k)
    m.dirs[k] = std::hypot(m.vx[k], m.vy[k]) > 1e-3 ? std::atan2(m.vy[k], m.vx[k])
                                                    : (k ? m.dirs[k - 1] : 0.0);
  return m;
}

TruthSample SampleAt(const TruthParams& t, const Path& p, const Motion& m, std::size_t k,
                     double fn_N) {
  const double half = t.area_m / 2;
  return {.x_m = p.x[k],
          .y_m = p.y[k],
          .u = p.x[k] / half,
          .w = p.y[k] / half,
          .d_m = m.d[k],
          .ddot_mps = m.dd[k],
          .speed_mps = std::hypot(m.vx[k], m.vy[k]),
          .dir_rad = m.dirs[k],
          .fn_N = fn_N,
          .rate_hz = t.rate_hz};
}

// 2. The full normal force with damping.
void NormalForce(const TruthParams& t, const TruthEffects& fx, const Path& p, const Motion& m,
                 SimulatedMeasurement& out) {
  const double half = t.area_m / 2;
  for (std::size_t k = 0; k < p.x.size(); ++k) {
    if (m.d[k] <= 0) continue;
    const NormalTerms n = fx.Normal(SampleAt(t, p, m, k, 0));
    const double dn = std::pow(m.d[k] / 1e-3, n.n);
    const double K = t.K1mm_N * (1 + t.K_position_amp * p.x[k] / half);
    const double f = dn * (K + n.B * m.dd[k]) + n.extra_N;
    out.fn_clean[k] = std::max(0.0, f);
  }
}

// The friction force (without the viscous term) at sample k, the bristle state F carried
// from sample to sample: a Dahl bristle by explicit Euler over 20 substeps of the sample's
// displacement, or without pre-sliding Coulomb smoothed over 0.5 mm/s.
void Bristle(const TruthFrictionTerms& f, double fc, const Path& p, const Motion& m,
             const SimulatedMeasurement& out, std::size_t k, double& Fx, double& Fy) {
  const double v = std::hypot(m.vx[k], m.vy[k]);
  if (fc > 0 && f.kappa_N_per_m > 0) {
    if (k == 0 || out.fn_clean[k - 1] <= 0) {
      Fx = Fy = 0;
      return;
    }
    const double sx = (p.x[k] - p.x[k - 1]) / 20, sy = (p.y[k] - p.y[k - 1]) / 20,
                 sl = std::hypot(sx, sy);
    for (int j = 0; j < 20; ++j) {
      Fx += f.kappa_N_per_m * (sx - sl * Fx / fc);
      Fy += f.kappa_N_per_m * (sy - sl * Fy / fc);
    }
    const double mag = std::hypot(Fx, Fy);
    if (mag > fc) Fx *= fc / mag, Fy *= fc / mag;
  } else if (fc > 0 && v > 0) {
    const double g = fc * std::tanh(v / 0.5e-3) / v;
    Fx = g * m.vx[k];
    Fy = g * m.vy[k];
  } else {
    Fx = Fy = 0;  // no friction level, or at rest without pre-sliding
  }
}

// 3. Friction: the effects' Coulomb level and bristle, plus the viscous term.
void FrictionForce(const TruthParams& t, const TruthEffects& fx, const Path& p, const Motion& m,
                   SimulatedMeasurement& out) {
  const std::size_t N = p.x.size();
  double Fx = 0, Fy = 0;
  for (std::size_t k = 0; k < N; ++k) {
    const double fn = out.fn_clean[k];
    if (fn <= 0) {
      Fx = Fy = 0;
      continue;
    }
    const TruthSample s = SampleAt(t, p, m, k, fn);
    const double drift = 1 + t.mu_drift * (static_cast<double>(k) / static_cast<double>(N) - 0.5);
    const TruthFrictionTerms f = fx.Friction(s, drift);
    const sim_truth::StribeckFriction law{
        .mu_k = f.mu_k * f.mu_scale, .dmu_s = f.dmu_s, .stribeck_speed_mps = f.stribeck_speed_mps};
    Bristle(f, fn * law.Mu(s.speed_mps), p, m, out, k, Fx, Fy);
    out.ftx_clean[k] = -(Fx + f.mu_b_Ns_per_m * m.vx[k]);
    out.fty_clean[k] = -(Fy + f.mu_b_Ns_per_m * m.vy[k]);
  }
}

// 4. Vibration: AR(2) resonance excited while sliding in contact, as the effects shape it.
std::vector<double> Vibration(const TruthParams& t, const TruthEffects& fx, const Path& p,
                              const Motion& m, Rng& rng, SimulatedMeasurement& out) {
  const std::size_t N = p.x.size();
  const double fs = t.rate_hz, r = 0.85;
  std::vector<double> acc(N);
  for (std::size_t k = 0; k < N; ++k) {
    const double fn = out.fn_clean[k];
    const TruthSample s = SampleAt(t, p, m, k, fn);
    const TruthVibrationTerms v = fx.Vibration(s, t.vib_sigma * t.vib_sigma);
    const double a1 = 2 * r * std::cos(2 * kPi * v.resonance_hz / fs), a2 = -r * r;
    const double pw = fn > 0 && s.speed_mps > 1e-3 ? v.power * (1 - r) : 0.0;
    const double prev1 = k ? acc[k - 1] : 0, prev2 = k > 1 ? acc[k - 2] : 0;
    acc[k] = a1 * prev1 + a2 * prev2 + std::sqrt(pw) * rng.Normal();
    out.acc_state[k] = {pw, a1, a2, t.acc_noise * t.acc_noise};
  }
  return acc;
}

// 5. The measurement, with sensor noise.
void WriteMeasurement(const TruthParams& t, const Path& p, const Motion& mo,
                      const std::vector<double>& acc, Rng& rng, SimulatedMeasurement& out) {
  const std::size_t N = p.x.size();
  const double dt = 1 / t.rate_hz;
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
    row.p_m = {p.x[k] + t.pos_noise_m * rng.Normal(), p.y[k] + t.pos_noise_m * rng.Normal(),
               -mo.d[k] + t.pos_noise_m * rng.Normal()};
    row.v_mps = {mo.vx[k] + t.vel_noise_mps * rng.Normal(),
                 mo.vy[k] + t.vel_noise_mps * rng.Normal(),
                 -mo.dd[k] + t.vel_noise_mps * rng.Normal()};
    row.f_N = {out.ftx_clean[k] + t.force_noise_N * rng.Normal(),
               out.fty_clean[k] + t.force_noise_N * rng.Normal(),
               out.fn_clean[k] + t.force_noise_N * rng.Normal()};
    row.acc_mps2 = acc[k] + t.acc_noise * rng.Normal();
    m.row_lines[k] = static_cast<int>(k) + 1;
  }
}

}  // namespace

SimulatedMeasurement Simulate(const TruthParams& tp) {
  TruthParams t = tp;
  if (t.effects.empty()) t.effects = BaselineEffects();
  const TruthEffects fx = Resolve(t);
  Rng rng(t.seed);
  const Path path = Strokes(t, rng);
  const Motion motion = Move(t, fx, path);
  const std::size_t N = path.x.size();
  SimulatedMeasurement out;
  out.truth = t;
  out.fn_clean.resize(N);
  out.ftx_clean.resize(N);
  out.fty_clean.resize(N);
  out.acc_state.resize(N);
  NormalForce(t, fx, path, motion, out);
  FrictionForce(t, fx, path, motion, out);
  const auto acc = Vibration(t, fx, path, motion, rng, out);
  WriteMeasurement(t, path, motion, acc, rng, out);
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
  m.Set(key::kK1mm_N, t.K1mm_N);
  for (const auto& name : m.effects) {
    const Effect& e = *FindEffect(name);
    const auto p = TruthValues(t, e);
    e.TruthToModel(p.data(), t.area_m / 2, &m);
  }
  return m;
}

Errors NoiseFloor(const SimulatedMeasurement& sim, const Replay& r, Split split) {
  auto p = Predict(TruthModel(sim, r), r);
  p.band_power = ExpectedBandPower(sim, r);
  return ComputeErrors(r, p, split);
}

}  // namespace hapticlab::modeling::wb
