// The model-versus-measurement workbench: replay, prediction, errors, fitting, comparison and
// diagnosis (DESIGN.md §4). Effects live in effects/, one file each.

#include "hapticlab/modeling/workbench.hpp"

#include <ceres/ceres.h>
#include <fftw3.h>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <functional>
#include <cmath>
#include <mutex>
#include <numbers>
#include <numeric>
#include <set>
#include <stdexcept>
#include <thread>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/modeling/contact.hpp"

namespace hapticlab::modeling::wb {
namespace {

constexpr double kMm = 1e-3;
constexpr double kPreslidingSpeed_mps = 0.5e-3;
constexpr double kSlidingSpeed_mps = 3e-3;
constexpr double kVibrationRidge = 1.0;  // see FitVibration
// Clusters of the jackknife covariance: this many consecutive 1 s blocks, so that a cluster spans
// several strokes and rests and the residual's correlation along a stroke stays inside it.
constexpr int kClusterBlocks = 3;

// The core every model has: the contact stiffness K (force at 1 mm penetration).
class Core final : public Effect {
 public:
  std::string_view name() const override { return "core"; }
  Channel channel() const override { return Channel::kNormal; }
  std::string_view description() const override { return "contact stiffness"; }
  std::vector<ParamSpec> Params(const Replay& r) const override {
    // Initial K: median of f_n / (d / 1 mm) over samples in contact.
    std::vector<double> k;
    for (const auto& s : r.s)
      if (s.contact && s.d_m > 1e-5) k.push_back(s.fn_N / (s.d_m / kMm));
    double init = 1;
    if (!k.empty()) {
      std::nth_element(k.begin(), k.begin() + k.size() / 2, k.end());
      init = std::max(k[k.size() / 2], 1e-3);
    }
    return {{"K1mm_N", "N", init, 1e-6, 1e6, init, true, "normal force at 1 mm penetration"}};
  }
  void Normal(const double* p, const Replay::Sample&, NormalTerms& t) const override { t.K = p[0]; }
  EvidenceNote Evidence(const Replay&, const Residuals&) const override { return {}; }
};
const Core kCore;

const Effect* Lookup(std::string_view name) { return name == "core" ? &kCore : FindEffect(name); }

// An effect with its parameter values in the order of its ParamSpec list.
struct Resolved {
  const Effect* e;
  std::string name;
  std::vector<ParamSpec> specs;
  std::vector<double> p;
};

std::vector<Resolved> Resolve(const Model& m, const Replay& r, Channel c) {
  std::vector<Resolved> out;
  std::vector<std::string> names;
  if (c == Channel::kNormal) names.push_back("core");
  for (const auto& n : m.effects) {
    const Effect* e = FindEffect(n);
    if (e && e->channel() == c) names.push_back(n);
  }
  for (const auto& n : names) {
    const Effect* e = Lookup(n);
    Resolved x{e, n, e->Params(r), {}};
    const auto it = m.params.find(n);
    for (const auto& s : x.specs) {
      double v = s.init;
      if (it != m.params.end()) {
        const auto jt = it->second.find(s.name);
        if (jt != it->second.end()) v = jt->second;
      }
      x.p.push_back(v);
    }
    out.push_back(std::move(x));
  }
  return out;
}

void Store(Model* m, const std::vector<Resolved>& res) {
  for (const auto& x : res)
    for (std::size_t i = 0; i < x.specs.size(); ++i) m->params[x.name][x.specs[i].name] = x.p[i];
}

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
  for (std::size_t i = 0; i < r.s.size(); ++i) {
    const auto& s = r.s[i];
    if (!s.contact) {
      Fx = Fy = 0;
      ftx[i] = fty[i] = 0;
      prev_contact = false;
      continue;
    }
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

}  // namespace

const char* ChannelName(Channel c) {
  switch (c) {
    case Channel::kNormal: return "normal_force";
    case Channel::kFriction: return "friction";
    case Channel::kVibration: return "vibration";
  }
  return "?";
}

const Effect* FindEffect(std::string_view name) {
  for (const auto& e : Catalogue())
    if (e->name() == name) return e.get();
  return nullptr;
}

std::vector<std::string> BaselineEffects() {
  return {"coulomb", "viscous", "dahl", "hc-damping", "hc-exponent", "vibration-speed", "vibration-force"};
}

bool Model::Has(std::string_view e) const { return std::find(effects.begin(), effects.end(), e) != effects.end(); }

// Centre value of a quadratic Savitzky-Golay fit over rows i-h..i+h into *out (closed-form
// weights (3 (3h^2 + 3h - 1) - 15 j^2) / ((2h-1)(2h+1)(2h+3)), hand-written: a few lines); false,
// *out untouched, where the window leaves the measurement or a row fails `use`.
template <class Value, class Use>
bool SavGol2(const Measurement& m, std::size_t i, std::size_t h, Value value, Use use, double* out) {
  if (h < 2 || i < h || i + h >= m.rows.size()) return false;
  const double hm = static_cast<double>(h);
  const double norm = (2 * hm - 1) * (2 * hm + 1) * (2 * hm + 3), c0 = 3 * (3 * hm * hm + 3 * hm - 1);
  double sg = 0;
  for (std::size_t k = i - h; k <= i + h; ++k) {
    if (!use(m.rows[k])) return false;
    const double j = static_cast<double>(k) - static_cast<double>(i);
    sg += (c0 - 15 * j * j) / norm * value(m.rows[k]);
  }
  *out = sg;
  return true;
}

// ---------------------------------------------------------------------------------------------
Replay PrepareReplay(const Measurement& m, const ReplayOptions& o) {
  Replay r;
  r.file = m.file;
  r.block_s = o.block_s;
  r.position_resolution_m = o.position_resolution_m;
  if (!(o.position_resolution_m > 0)) {
    // Position noise from rows at rest in contact: the second difference of white noise has
    // variance 6 sigma^2, its median absolute value 0.6745 of its SD.
    std::vector<double> d2;
    for (std::size_t i = 1; i + 1 < m.rows.size(); ++i) {
      const auto &a = m.rows[i - 1], &b = m.rows[i], &c = m.rows[i + 1];
      if (b.v_mps.head<2>().norm() > 1e-3 || !(b.f_N.z() > o.contact_force_N)) continue;
      for (int k = 0; k < 2; ++k) d2.push_back(std::abs(a.p_m[k] - 2 * b.p_m[k] + c.p_m[k]));
    }
    r.position_resolution_m = 1e-6;
    if (d2.size() >= 200) {
      std::nth_element(d2.begin(), d2.begin() + static_cast<std::ptrdiff_t>(d2.size() / 2), d2.end());
      const double sigma = d2[d2.size() / 2] / 0.674489750196 / std::sqrt(6.0);
      r.position_resolution_m = std::clamp(4 * sigma, 0.05e-6, 5e-6);
    }
  }
  if (m.rows.size() < 2) throw InputError(m.file, 0, "", "a measurement needs at least two rows");
  std::vector<double> dt;
  for (std::size_t i = 1; i < m.rows.size(); ++i) dt.push_back(m.rows[i].t_s - m.rows[i - 1].t_s);
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  double rate = 1.0 / dt[dt.size() / 2];
  if (std::abs(rate - std::round(rate)) < 1e-6 * rate) rate = std::round(rate);  // time stamps' rounding
  const int stride = std::max(1, static_cast<int>(std::lround(rate / o.max_force_rate_hz)));
  const auto half_load = static_cast<std::size_t>(std::max(0L, std::lround(0.5 * o.load_smoothing_s * rate)));
  const auto half_pos = static_cast<std::size_t>(std::max(0L, std::lround(0.5 * o.position_smoothing_s * rate)));
  if (!(o.position_resolution_m > 0) && half_pos >= 2) {
    // The smoothed positions' noise: the centre weight is the variance factor of the SG fit.
    const double hm = static_cast<double>(half_pos);
    r.position_resolution_m = std::max(0.05e-6, r.position_resolution_m * std::sqrt(3 * (3 * hm * hm + 3 * hm - 1) /
                                                                        ((2 * hm - 1) * (2 * hm + 1) * (2 * hm + 3))));
  }
  r.rate_hz = rate / stride;
  const double t0 = m.rows.front().t_s;
  double dir = 0;
  bool any = false;
  for (std::size_t i = 0; i < m.rows.size(); i += stride) {
    const auto& row = m.rows[i];
    Replay::Sample s{};
    s.t_s = row.t_s;
    s.x_m = row.p_m.x();
    s.y_m = row.p_m.y();
    {
      const auto all = [](const MeasurementRow&) { return true; };
      SavGol2(m, i, half_pos, [](const MeasurementRow& w) { return w.p_m.x(); }, all, &s.x_m);
      SavGol2(m, i, half_pos, [](const MeasurementRow& w) { return w.p_m.y(); }, all, &s.y_m);
    }
    s.d_m = std::max(0.0, -row.p_m.z());
    s.ddot_mps = -row.v_mps.z();
    s.vx_mps = row.v_mps.x();
    s.vy_mps = row.v_mps.y();
    s.speed_mps = std::hypot(s.vx_mps, s.vy_mps);
    if (s.speed_mps > 1e-3) dir = std::atan2(s.vy_mps, s.vx_mps);  // at rest: the last motion's
    s.dir_rad = dir;
    s.fn_N = row.f_N.z();
    {
      // Quadratic Savitzky-Golay smoothing (closed-form centre weights, hand-written: five lines)
      // where the whole window is in contact: a moving average would bias the load by
      // W^2 f''/24 wherever it curves (ends of strokes, pokes), a bias that friction's speed
      // terms absorb (mu_b +1.5 % on noise-free free-hand data). Elsewhere the mean of the rows
      // in contact.
      double sum = 0;
      int count = 0;
      const std::size_t lo = i >= half_load ? i - half_load : 0, hi = std::min(m.rows.size() - 1, i + half_load);
      for (std::size_t k = lo; k <= hi; ++k)
        if (m.rows[k].f_N.z() > o.contact_force_N) sum += m.rows[k].f_N.z(), ++count;
      s.fload_N = count ? sum / count : s.fn_N;
      if (o.load_savgol)
        SavGol2(
            m, i, half_load, [](const MeasurementRow& w) { return w.f_N.z(); },
            [&](const MeasurementRow& w) { return w.f_N.z() > o.contact_force_N; }, &s.fload_N);
    }
    s.ftx_N = row.f_N.x();
    s.fty_N = row.f_N.y();
    s.contact = s.fn_N > o.contact_force_N;
    s.block = static_cast<int>(std::floor((row.t_s - t0) / o.block_s));
    s.row = static_cast<int>(i);
    if (s.contact) {
      if (!any) r.x_min = r.x_max = s.x_m, r.y_min = r.y_max = s.y_m;
      any = true;
      r.x_min = std::min(r.x_min, s.x_m), r.x_max = std::max(r.x_max, s.x_m);
      r.y_min = std::min(r.y_min, s.y_m), r.y_max = std::max(r.y_max, s.y_m);
    }
    r.s.push_back(s);
  }
  if (!any)
    throw InputError(m.file, 0, "fz_N", fmt::format("no sample in contact (fz_N > {} N)", o.contact_force_N));

  if (!m.has_acceleration) return r;
  r.has_vibration = true;
  r.acc_rate_hz = rate;
  int n = 64;
  while (n * 2 <= o.window_s * rate * 1.5) n *= 2;
  const double fmax = std::min(1000.0, 0.45 * rate);
  if (!o.band_edges_hz.empty()) {
    if (o.band_edges_hz.back() > 0.5 * rate)
      throw InputError(m.file, 0, "acc_mps2",
                       fmt::format("the model's vibration bands reach {:.0f} Hz, above this measurement's Nyquist "
                                   "frequency {:.0f} Hz",
                                   o.band_edges_hz.back(), 0.5 * rate));
    r.band_lo_hz.assign(o.band_edges_hz.begin(), o.band_edges_hz.end() - 1);
    r.band_hi_hz.assign(o.band_edges_hz.begin() + 1, o.band_edges_hz.end());
  } else {
    for (int b = 0; b < o.bands; ++b) {
      r.band_lo_hz.push_back(20 * std::pow(fmax / 20, static_cast<double>(b) / o.bands));
      r.band_hi_hz.push_back(20 * std::pow(fmax / 20, static_cast<double>(b + 1) / o.bands));
    }
  }
  const int nb = static_cast<int>(r.band_lo_hz.size());
  // Bins of each band (at least the nearest bin).
  std::vector<std::vector<int>> bins(nb);
  for (int b = 0; b < nb; ++b) {
    for (int k = 1; k < n / 2; ++k) {
      const double f = k * rate / n;
      if (f >= r.band_lo_hz[b] && f < r.band_hi_hz[b]) bins[b].push_back(k);
    }
    if (bins[b].empty())
      bins[b].push_back(std::clamp(static_cast<int>(std::lround(std::sqrt(r.band_lo_hz[b] * r.band_hi_hz[b]) * n / rate)),
                                   1, n / 2 - 1));
  }
  std::vector<double> win(n);
  double wss = 0;
  for (int k = 0; k < n; ++k) {
    win[k] = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * k / n);
    wss += win[k] * win[k];
  }
  double* in = fftw_alloc_real(n);
  fftw_complex* out = fftw_alloc_complex(n / 2 + 1);
  static std::mutex plan_mutex;  // FFTW's planner is not thread-safe
  fftw_plan plan;
  {
    std::lock_guard<std::mutex> lock(plan_mutex);
    plan = fftw_plan_dft_r2c_1d(n, in, out, FFTW_ESTIMATE);
  }
  for (std::size_t w0 = 0; w0 + n <= m.rows.size(); w0 += n / 4) {
    double sp = 0, f = 0, mean = 0, wsum = 0, sp2 = 0, f2 = 0;
    std::array<double, 4> d{};
    bool contact = true;
    for (int k = 0; k < n; ++k) {
      const auto& row = m.rows[w0 + k];
      if (!(row.f_N.z() > o.contact_force_N)) contact = false;
      const double v = row.v_mps.head<2>().norm();
      sp += v, sp2 += v * v;
      f += row.f_N.z(), f2 += row.f_N.z() * row.f_N.z();
      mean += row.acc_mps2;
      if (v > 1e-4) {
        const double ph = std::atan2(row.v_mps.y(), row.v_mps.x());
        d[0] += v * std::cos(ph), d[1] += v * std::sin(ph), d[2] += v * std::cos(2 * ph), d[3] += v * std::sin(2 * ph);
        wsum += v;
      }
    }
    sp /= n, f /= n, mean /= n;
    if (!contact || sp < o.min_speed_mps) continue;
    // Only steady windows: a spectrum is a property of a condition, not of a transition.
    const double sv = std::sqrt(std::max(0.0, sp2 / n - sp * sp)), sf = std::sqrt(std::max(0.0, f2 / n - f * f));
    if (sv > o.max_variation * sp || sf > o.max_variation * f) continue;
    for (auto& x : d) x /= std::max(wsum, 1e-12);
    for (int k = 0; k < n; ++k) in[k] = (m.rows[w0 + k].acc_mps2 - mean) * win[k];
    fftw_execute(plan);
    Replay::Window w{};
    w.t_s = m.rows[w0].t_s;
    w.speed_mps = sp;
    w.force_N = f;
    w.dir = d;
    w.block = static_cast<int>(std::floor((m.rows[w0 + n / 2].t_s - t0) / o.block_s));
    w.row0 = static_cast<int>(w0);
    w.rows = n;
    for (int b = 0; b < nb; ++b) {
      double p = 0;
      for (const int k : bins[b]) p += (out[k][0] * out[k][0] + out[k][1] * out[k][1]) / wss;
      w.band_power.push_back(std::max(p / static_cast<double>(bins[b].size()), 1e-300));
    }
    r.windows.push_back(std::move(w));
  }
  {
    std::lock_guard<std::mutex> lock(plan_mutex);
    fftw_destroy_plan(plan);
  }
  fftw_free(in);
  fftw_free(out);
  return r;
}

// ---------------------------------------------------------------------------------------------
void AddEffects(Model* m, const std::vector<std::string>& names, const Replay& r) {
  std::vector<std::string> todo;
  std::function<void(const std::string&)> add = [&](const std::string& n) {
    const Effect* e = FindEffect(n);
    if (!e) {
      std::string list;
      for (const auto& c : Catalogue()) list += (list.empty() ? "" : ", ") + std::string(c->name());
      throw std::invalid_argument(fmt::format("unknown effect '{}'; the catalogue has: {}", n, list));
    }
    for (const auto dep : e->requires_effects()) add(std::string(dep));
    if (!m->Has(n) && std::find(todo.begin(), todo.end(), n) == todo.end()) todo.push_back(n);
  };
  for (const auto& n : names) add(n);
  for (const auto& n : todo) {
    m->effects.push_back(n);
    for (const auto& s : FindEffect(n)->Params(r)) m->params[n][s.name] = s.init;
  }
  // Keep the catalogue's order so files and reports are stable.
  std::sort(m->effects.begin(), m->effects.end(), [](const std::string& a, const std::string& b) {
    const auto& c = Catalogue();
    auto idx = [&](const std::string& n) {
      for (std::size_t i = 0; i < c.size(); ++i)
        if (c[i]->name() == n) return i;
      return c.size();
    };
    return idx(a) < idx(b);
  });
  if (!m->params.count("core"))
    for (const auto& s : kCore.Params(r)) m->params["core"][s.name] = s.init;
}

// ---------------------------------------------------------------------------------------------
Prediction Predict(const Model& m, const Replay& r) {
  Prediction p;
  const auto nrm = Resolve(m, r, Channel::kNormal);
  p.fn_N.resize(r.s.size());
  for (std::size_t i = 0; i < r.s.size(); ++i) p.fn_N[i] = NormalForce(nrm, r.s[i]);
  p.ftx_N.resize(r.s.size());
  p.fty_N.resize(r.s.size());
  FrictionForces(Resolve(m, r, Channel::kFriction), r, p.ftx_N.data(), p.fty_N.data());
  if (m.HasVibration() && r.has_vibration) {
    const auto vib = Resolve(m, r, Channel::kVibration);
    const auto& core = m.coef.at("core");
    const std::size_t nb = r.band_lo_hz.size();
    if (core.size() != nb)
      throw InputError(r.file, 0, "acc_mps2",
                       fmt::format("the model's vibration has {} bands, the measurement's analysis {}", core.size(), nb));
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
        if (const auto lo = m.coef.find("range_lo"); lo != m.coef.end() && lo->second.size() == nb)
          lp = std::clamp(lp, lo->second[b], m.coef.at("range_hi")[b]);
        bp[b] = std::exp(lp);
      }
      p.band_power.push_back(std::move(bp));
    }
  }
  return p;
}

Residuals ComputeResiduals(const Model&, const Replay& r, const Prediction& p) {
  Residuals res;
  const std::size_t n = r.s.size();
  res.normal_N.assign(n, 0);
  res.friction_N.assign(n, 0);
  res.ratio.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& s = r.s[i];
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
    for (std::size_t b = 0; b < p.band_power[w].size(); ++b) lb.push_back(std::log(r.windows[w].band_power[b] / p.band_power[w][b]));
    res.log_band.push_back(std::move(lb));
  }
  return res;
}

Errors ComputeErrors(const Replay& r, const Prediction& p, Split split) {
  Errors e;
  double sn = 0, nn = 0, st = 0, nt = 0, sr = 0;
  int nr = 0;
  for (std::size_t i = 0; i < r.s.size(); ++i) {
    const auto& s = r.s[i];
    if (!s.contact || !InSplit(s.block, split)) continue;
    const double en = (s.fn_N - p.fn_N[i]) * (s.fn_N - p.fn_N[i]);
    const double dx = s.ftx_N - p.ftx_N[i], dy = s.fty_N - p.fty_N[i], et = dx * dx + dy * dy;
    sn += en, nn += s.fn_N * s.fn_N;
    st += et, nt += s.ftx_N * s.ftx_N + s.fty_N * s.fty_N;
    e.block_sse["normal_force"][s.block] += en;
    e.block_sse["friction"][s.block] += et;
    if (s.speed_mps >= kSlidingSpeed_mps && s.fn_N > 0.05) {
      const double d = (std::hypot(s.ftx_N, s.fty_N) - std::hypot(p.ftx_N[i], p.fty_N[i])) / s.fn_N;
      sr += d * d, ++nr;
    }
  }
  int count = 0;
  if (nn > 0) {
    e.channel["normal_force"] = std::sqrt(sn / nn);
    e.norm["normal_force"] = nn;
    ++count;
  }
  if (nt > 0) {
    e.channel["friction"] = std::sqrt(st / nt);
    e.norm["friction"] = nt;
    ++count;
  }
  // RMS in newtons over the counted samples.
  int ns = 0;
  for (const auto& s : r.s) ns += s.contact && InSplit(s.block, split);
  e.rms["normal_force_N"] = ns ? std::sqrt(sn / ns) : 0;
  e.rms["tangential_N"] = ns ? std::sqrt(st / ns) : 0;
  e.rms["friction_ratio"] = nr ? std::sqrt(sr / nr) : 0;
  if (!p.band_power.empty()) {
    double se = 0;
    int nw = 0;
    for (std::size_t w = 0; w < r.windows.size(); ++w) {
      if (!InSplit(r.windows[w].block, split)) continue;
      double num = 0, den = 0;
      for (std::size_t b = 0; b < p.band_power[w].size(); ++b) {
        const double a = std::sqrt(r.windows[w].band_power[b]), q = std::sqrt(p.band_power[w][b]);
        num += (a - q) * (a - q);
        den += a * a;
      }
      const double es = std::sqrt(num / den);
      se += es, ++nw;
      e.block_sse["vibration"][r.windows[w].block] += es;
    }
    if (nw > 0) {
      e.channel["vibration"] = se / nw;
      e.norm["vibration"] = nw;
      e.rms["vibration_Es"] = se / nw;
      ++count;
    }
  }
  double sum = 0;
  for (const auto& [k, v] : e.channel) sum += v;
  e.overall = count ? sum / count : 0;
  return e;
}

// ---------------------------------------------------------------------------------------------
namespace {

// Ceres functor over one channel's fitted parameters (scaled), replaying the whole channel.
struct ChannelCost {
  Channel channel;
  const Replay* r;
  std::vector<int> idx;                          // samples with residuals
  mutable std::vector<Resolved> eff;
  std::vector<std::pair<int, int>> slots;         // (effect, parameter) per unknown
  std::vector<double> scale;
  mutable std::vector<double> ftx, fty;

  void Set(const double* x) const {
    for (std::size_t k = 0; k < slots.size(); ++k) eff[slots[k].first].p[slots[k].second] = x[k] * scale[k];
  }
  bool operator()(double const* const* x, double* res) const {
    Set(x[0]);
    if (channel == Channel::kNormal) {
      for (std::size_t k = 0; k < idx.size(); ++k) res[k] = NormalForce(eff, r->s[idx[k]]) - r->s[idx[k]].fn_N;
    } else {
      FrictionForces(eff, *r, ftx.data(), fty.data());
      for (std::size_t k = 0; k < idx.size(); ++k) {
        res[2 * k] = ftx[idx[k]] - r->s[idx[k]].ftx_N;
        res[2 * k + 1] = fty[idx[k]] - r->s[idx[k]].fty_N;
      }
    }
    for (std::size_t k = 0; k < (channel == Channel::kNormal ? 1 : 2) * idx.size(); ++k)
      if (!std::isfinite(res[k])) return false;
    return true;
  }
};

// Two-sided 97.5 % quantile of Student's t with `dof` degrees of freedom (Cornish-Fisher
// expansion about the normal quantile; within 1e-3 for dof >= 5).
double TQuantile975(int dof) {
  const double z = 1.959963984540054, v = std::max(dof, 1);
  return z + (z * z * z + z) / (4 * v) + (5 * std::pow(z, 5) + 16 * z * z * z + 3 * z) / (96 * v * v) +
         (3 * std::pow(z, 7) + 19 * std::pow(z, 5) + 17 * z * z * z - 15 * z) / (384 * v * v * v);
}

FitSummary FromCeres(const std::string& what, const ceres::Solver::Summary& sum) {
  FitSummary f;
  f.what = what;
  f.method = "ceres (bounded trust region, numeric derivatives of the replay)";
  switch (sum.termination_type) {
    case ceres::CONVERGENCE: f.termination = "converged"; break;
    case ceres::NO_CONVERGENCE: f.termination = "iteration limit"; break;
    case ceres::USER_SUCCESS: f.termination = "converged"; break;
    default: f.termination = "failed"; break;
  }
  f.message = sum.message;
  f.iterations = sum.num_successful_steps + sum.num_unsuccessful_steps;
  f.initial_cost = sum.initial_cost;
  f.final_cost = sum.final_cost;
  f.usable = f.termination == "converged" && std::isfinite(sum.final_cost);
  return f;
}

ChannelFit FitForceChannel(Model* m, const Replay& r, Channel c, const FitOptions& o) {
  ChannelFit out;
  out.channel = c;
  out.summary.what = ChannelName(c);
  auto* cost = new ChannelCost{c, &r, {}, Resolve(*m, r, c), {}, {}, {}, {}};
  for (std::size_t i = 0; i < r.s.size(); ++i)
    if (r.s[i].contact && InSplit(r.s[i].block, o.split) && (c != Channel::kNormal || r.s[i].fn_N <= o.max_normal_force_N))
      cost->idx.push_back(static_cast<int>(i));
  // Algorithm 1 starts a friction model that has never been fitted (coulomb and dahl at their
  // initial values): the Ceres refinement is then the joint batch step of the dissertation.
  if (c == Channel::kFriction && o.algorithm1_init && m->Has("coulomb") && m->Has("dahl")) {
    auto slot = [&](const std::string& e, const std::string& p) -> double* {
      for (auto& x : cost->eff)
        if (x.name == e)
          for (std::size_t k = 0; k < x.specs.size(); ++k)
            if (x.specs[k].name == p) return &x.p[k];
      return nullptr;
    };
    auto init = [&](const std::string& e, const std::string& p) {
      for (const auto& spec : FindEffect(e)->Params(r))
        if (spec.name == p) return spec.init;
      return std::numeric_limits<double>::quiet_NaN();
    };
    double* mu_k = slot("coulomb", "mu_k");
    double* kappa = slot("dahl", "kappa");
    double* mu_b = slot("viscous", "mu_b");
    if (mu_k && kappa && *mu_k == init("coulomb", "mu_k") && *kappa == init("dahl", "kappa") &&
        (!mu_b || *mu_b == init("viscous", "mu_b"))) {
      try {
        const auto a = AlgorithmOne(r, o.split);
        if (std::isfinite(a.mu_k) && a.mu_k > 0) *mu_k = std::min(a.mu_k, 3.0);
        if (std::isfinite(a.kappa_N_per_m) && a.kappa_N_per_m > 0) *kappa = std::clamp(a.kappa_N_per_m, 10.0, 1e6);
        if (mu_b && std::isfinite(a.mu_b_Ns_per_m)) *mu_b = std::clamp(a.mu_b_Ns_per_m, 0.0, 1000.0);
      } catch (const InputError&) {
        // Too few pre-sliding or sliding samples for Algorithm 1: start from the neutral values.
      }
    }
  }
  std::vector<double> x, lo, hi;
  for (std::size_t e = 0; e < cost->eff.size(); ++e)
    for (std::size_t k = 0; k < cost->eff[e].specs.size(); ++k) {
      const auto& s = cost->eff[e].specs[k];
      if (!s.fitted) continue;
      cost->slots.emplace_back(static_cast<int>(e), static_cast<int>(k));
      cost->scale.push_back(s.scale);
      x.push_back(std::clamp(cost->eff[e].p[k], s.lo, s.hi) / s.scale);
      lo.push_back(s.lo / s.scale);
      hi.push_back(s.hi / s.scale);
    }
  out.samples = static_cast<int>(cost->idx.size());
  if (x.empty() || cost->idx.size() < x.size() * 3) {
    out.summary.termination = x.empty() ? "not run (no fitted parameter)" : "not run (too few samples)";
    out.summary.usable = x.empty();
    delete cost;
    return out;
  }
  cost->ftx.resize(r.s.size());
  cost->fty.resize(r.s.size());
  const int per = c == Channel::kNormal ? 1 : 2;
  const int nres = static_cast<int>(cost->idx.size()) * per;
  auto* fn = new ceres::DynamicNumericDiffCostFunction<ChannelCost, ceres::CENTRAL>(cost);
  fn->AddParameterBlock(static_cast<int>(x.size()));
  fn->SetNumResiduals(nres);
  ceres::Problem problem;
  problem.AddResidualBlock(fn, nullptr, x.data());
  for (std::size_t k = 0; k < x.size(); ++k) {
    problem.SetParameterLowerBound(x.data(), static_cast<int>(k), lo[k]);
    problem.SetParameterUpperBound(x.data(), static_cast<int>(k), hi[k]);
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = 1e-10;
  so.parameter_tolerance = 1e-10;
  so.logging_type = ceres::SILENT;
  so.num_threads = 1;
  ceres::Solver::Summary sum;
  ceres::Solve(so, &problem, &sum);
  out.summary = FromCeres(ChannelName(c), sum);
  // Copy the optimum back (the functor's copy holds the last evaluated point, not the best).
  std::vector<Resolved> eff = cost->eff;
  for (std::size_t k = 0; k < cost->slots.size(); ++k) eff[cost->slots[k].first].p[cost->slots[k].second] = x[k] * cost->scale[k];
  Store(m, eff);
  const std::size_t np = x.size();
  for (std::size_t k = 0; k < np; ++k) {
    const auto& x_eff = eff[cost->slots[k].first];
    const auto& spec = x_eff.specs[cost->slots[k].second];
    ParamEstimate pe;
    pe.effect = x_eff.name;
    pe.name = spec.name;
    pe.value = x[k] * cost->scale[k];
    pe.lo95 = pe.hi95 = pe.value;
    // At a bound: within 1e-6 of the parameter's range (or of its scale, for open ranges).
    const double tol = 1e-6 * std::max(1.0, std::min(hi[k] - lo[k], 1e6));
    const bool at_lo = x[k] - lo[k] <= tol, at_hi = hi[k] - x[k] <= tol;
    // A bound at exactly zero of a non-negative amplitude (mu_b, B, dmu_s) is its neutral value.
    pe.at_bound = at_hi || (at_lo && lo[k] != 0.0);
    if (pe.at_bound)
      out.summary.at_bounds.push_back(fmt::format("{}.{} at its {} bound ({:.6g})", pe.effect, pe.name,
                                                  at_hi ? "upper" : "lower", pe.value));
    out.params.push_back(pe);
  }
  if (!o.uncertainty) return out;

  // Sandwich covariance over the split's blocks, in scaled parameters, from a central-difference
  // Jacobian of the residuals at the optimum.
  Eigen::MatrixXd J(nres, static_cast<Eigen::Index>(np));
  std::vector<double> r0(nres), rp(nres), rm(nres), xs = x;
  const double* xp[1] = {xs.data()};
  (*cost)(xp, r0.data());
  for (std::size_t k = 0; k < np; ++k) {
    const double h = 1e-5 * std::max(1.0, std::abs(x[k]));
    std::copy(x.begin(), x.end(), xs.begin());
    xs[k] = x[k] + h;
    (*cost)(xp, rp.data());
    xs[k] = x[k] - h;
    (*cost)(xp, rm.data());
    for (int i = 0; i < nres; ++i) J(i, static_cast<Eigen::Index>(k)) = (rp[i] - rm[i]) / (2 * h);
  }
  // Cluster (delete-one-cluster) jackknife, by the one-step Gauss-Newton update
  // d_g = (J'J - J_g'J_g)^-1 J_g' r_g of leaving cluster g out: cov = (G-1)/G sum (d_g - d)(d_g - d)'.
  // The plain CR0 sandwich G/(G-1) (J'J)^-1 sum s_g s_g' (J'J)^-1 is biased low with the ten
  // clusters of a 30 s recording (it covered the truth in 15-17 of 20 seeds); the jackknife
  // (CR3, MacKinnon & White 1985; Cameron & Miller 2015, sec. VI) corrects for each cluster's
  // leverage.
  const auto npi = static_cast<Eigen::Index>(np);
  std::map<int, std::pair<Eigen::MatrixXd, Eigen::VectorXd>> cl;
  for (int i = 0; i < nres; ++i) {
    const int blk = r.s[cost->idx[i / per]].block / kClusterBlocks;
    auto it = cl.try_emplace(blk, Eigen::MatrixXd::Zero(npi, npi), Eigen::VectorXd::Zero(npi)).first;
    it->second.first += J.row(i).transpose() * J.row(i);
    it->second.second += J.row(i).transpose() * r0[static_cast<std::size_t>(i)];
  }
  const double G = static_cast<double>(cl.size());
  out.clusters = static_cast<int>(cl.size());
  if (G < 2) return out;
  const Eigen::MatrixXd JtJ = J.transpose() * J;
  std::vector<Eigen::VectorXd> d;
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(npi);
  for (const auto& [blk, a] : cl) {
    d.push_back((JtJ - a.first).completeOrthogonalDecomposition().pseudoInverse() * a.second);
    mean += d.back() / G;
  }
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(npi, npi);
  for (const auto& dg : d) cov += (G - 1) / G * (dg - mean) * (dg - mean).transpose();
  const double t = TQuantile975(out.clusters - 1);
  out.covariance.assign(np * np, 0);
  for (std::size_t a = 0; a < np; ++a)
    for (std::size_t b = 0; b < np; ++b)
      out.covariance[a * np + b] = cov(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) * cost->scale[a] * cost->scale[b];
  for (std::size_t k = 0; k < np; ++k) {
    auto& pe = out.params[k];
    pe.sd = std::sqrt(std::max(out.covariance[k * np + k], 0.0));
    pe.lo95 = pe.value - t * pe.sd;
    pe.hi95 = pe.value + t * pe.sd;
  }
  return out;
}

ChannelFit FitVibration(Model* m, const Replay& r, Split split) {
  ChannelFit out;
  out.channel = Channel::kVibration;
  out.summary.what = "vibration";
  out.summary.method = "linear least squares (ridge on the effect columns)";
  if (!r.has_vibration) {
    out.summary.termination = "not run (no acceleration)";
    return out;
  }
  const auto vib = Resolve(*m, r, Channel::kVibration);
  std::vector<std::size_t> use;
  for (std::size_t w = 0; w < r.windows.size(); ++w)
    if (InSplit(r.windows[w].block, split)) use.push_back(w);
  int cols = 1;
  for (const auto& x : vib) cols += x.e->VibrationColumns();
  out.samples = static_cast<int>(use.size());
  if (use.size() < static_cast<std::size_t>(cols) + 2) {
    out.summary.termination = "not run (too few vibration windows)";
    return out;
  }
  const std::size_t nb = r.band_lo_hz.size();
  Eigen::MatrixXd X(use.size(), cols);
  Eigen::MatrixXd Y(use.size(), nb);
  for (std::size_t k = 0; k < use.size(); ++k) {
    const auto row = VibrationRow(vib, r.windows[use[k]]);
    for (int c = 0; c < cols; ++c) X(k, c) = row[c];
    for (std::size_t b = 0; b < nb; ++b) Y(k, b) = std::log(r.windows[use[k]].band_power[b]);
  }
  // Ridge on the effect columns (not the intercept): a few dozen windows per band is little
  // data for a dozen coefficients, and exp() turns an over-fitted slope into a large error.
  Eigen::MatrixXd A = X.transpose() * X;
  for (int c = 1; c < cols; ++c) A(c, c) += kVibrationRidge;
  A(0, 0) += 1e-9;
  Eigen::MatrixXd C = A.ldlt().solve(X.transpose() * Y);  // cols x bands
  // ln of a periodogram is biased low (E ln chi2_2/2 = -0.577); set each band's level so the
  // predicted power equals the measured power on average.
  const Eigen::MatrixXd pred = X * C;
  m->coef.clear();
  m->coef["core"].resize(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    double ratio = 0;
    for (std::size_t k = 0; k < use.size(); ++k) ratio += std::exp(Y(k, b) - pred(k, b));
    m->coef["core"][b] = C(0, b) + std::log(ratio / static_cast<double>(use.size()));
  }
  int col = 1;
  for (const auto& x : vib) {
    const int c = x.e->VibrationColumns();
    auto& v = m->coef[x.name];
    v.assign(nb * c, 0);
    for (std::size_t b = 0; b < nb; ++b)
      for (int j = 0; j < c; ++j) v[b * c + j] = C(col + j, b);
    col += c;
  }
  // Predictions are kept within the measured range of each band (plus one e-fold), so an
  // extrapolated condition cannot predict absurd power.
  m->coef["range_lo"].resize(nb);
  m->coef["range_hi"].resize(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    m->coef["range_lo"][b] = Y.col(static_cast<Eigen::Index>(b)).minCoeff() - 1;
    m->coef["range_hi"][b] = Y.col(static_cast<Eigen::Index>(b)).maxCoeff() + 1;
  }
  m->band_edges_hz = r.band_lo_hz;
  m->band_edges_hz.push_back(r.band_hi_hz.back());
  Store(m, vib);
  double sse = 0;
  const Eigen::MatrixXd fitted = X * C;
  for (Eigen::Index k = 0; k < fitted.rows(); ++k)
    for (Eigen::Index b = 0; b < fitted.cols(); ++b) sse += std::pow(Y(k, b) - fitted(k, b), 2);
  out.summary.termination = "converged";
  out.summary.iterations = 1;
  out.summary.final_cost = 0.5 * sse;
  out.summary.usable = std::isfinite(sse);
  return out;
}

}  // namespace

FitReport Fit(Model* m, const Replay& r, const FitOptions& o) {
  FitReport rep;
  if (!m->params.count("core"))
    for (const auto& s : kCore.Params(r)) m->params["core"][s.name] = s.init;
  if (o.normal) rep.channels.push_back(FitForceChannel(m, r, Channel::kNormal, o));
  if (o.friction) rep.channels.push_back(FitForceChannel(m, r, Channel::kFriction, o));
  if (o.vibration && r.has_vibration) rep.channels.push_back(FitVibration(m, r, o.split));
  return rep;
}

bool FitReport::IsUsable() const {
  for (const auto& c : channels)
    if (!c.summary.usable) return false;
  return true;
}

const ChannelFit* FitReport::Find(Channel c) const {
  for (const auto& x : channels)
    if (x.channel == c) return &x;
  return nullptr;
}

// ---------------------------------------------------------------------------------------------
namespace {

struct Dim {
  std::string name;
  std::vector<double> edges;
  std::vector<std::string> labels;
};

std::vector<BinRow> Bin(const Dim& d, const std::vector<double>& key, const std::vector<double>& val,
                        const std::vector<char>& use) {
  std::vector<BinRow> rows(d.edges.size() - 1);
  for (std::size_t j = 0; j + 1 < d.edges.size(); ++j) {
    rows[j].label = d.labels.empty() ? fmt::format("{:g}-{:g}", d.edges[j], d.edges[j + 1]) : d.labels[j];
    rows[j].center = std::isfinite(d.edges[j + 1]) ? (d.edges[j] + d.edges[j + 1]) / 2 : d.edges[j];
  }
  for (std::size_t i = 0; i < key.size(); ++i) {
    if (!use[i]) continue;
    for (std::size_t j = 0; j + 1 < d.edges.size(); ++j)
      if (key[i] >= d.edges[j] && key[i] < d.edges[j + 1]) {
        rows[j].mean += val[i];
        rows[j].rms += val[i] * val[i];
        ++rows[j].n;
        break;
      }
  }
  for (auto& r : rows)
    if (r.n) r.mean /= r.n, r.rms = std::sqrt(r.rms / r.n);
  return rows;
}

}  // namespace

Comparison Compare(const Model& m, const Replay& r) {
  Comparison c;
  const auto p = Predict(m, r);
  c.errors = ComputeErrors(r, p, Split::kAll);
  const auto res = ComputeResiduals(m, r, p);
  const std::size_t n = r.s.size();
  const double inf = std::numeric_limits<double>::infinity(), pi = std::numbers::pi;
  std::vector<double> speed_mm(n), load(n), dir(n), tile(n), time(n), regime(n);
  std::vector<char> contact(n), sliding(n), moving(n);
  const double T0 = r.s.front().t_s, T1 = r.s.back().t_s + 1e-9;
  for (std::size_t i = 0; i < n; ++i) {
    const auto& s = r.s[i];
    speed_mm[i] = s.speed_mps * 1e3;
    load[i] = s.fn_N;
    dir[i] = s.dir_rad;
    const int tx = std::clamp(static_cast<int>(3 * (s.x_m - r.x_min) / std::max(r.x_max - r.x_min, 1e-9)), 0, 2);
    const int ty = std::clamp(static_cast<int>(3 * (s.y_m - r.y_min) / std::max(r.y_max - r.y_min, 1e-9)), 0, 2);
    tile[i] = 3 * ty + tx;
    time[i] = (s.t_s - T0) / (T1 - T0) * 10;
    regime[i] = s.speed_mps <= kPreslidingSpeed_mps ? 0 : (s.speed_mps < kSlidingSpeed_mps ? 1 : 2);
    contact[i] = s.contact;
    sliding[i] = s.contact && s.speed_mps >= kSlidingSpeed_mps;
    moving[i] = s.contact && s.speed_mps >= kPreslidingSpeed_mps;  // friction along the motion is defined
  }
  std::vector<double> dir_edges;
  std::vector<std::string> dir_labels;
  for (int k = 0; k <= 8; ++k) dir_edges.push_back(-pi + k * pi / 4 - pi / 8);
  for (int k = 0; k < 8; ++k) dir_labels.push_back(fmt::format("{:.0f} deg", -180 + 45.0 * k));
  // Directions near +180 belong to the first bin (-180).
  for (auto& d : dir)
    if (d >= pi - pi / 8) d -= 2 * pi;
  const Dim dims[] = {
      {"regime", {0, 1, 2, 3}, {"pre-sliding (<= 0.5 mm/s)", "transition (0.5-3 mm/s)", "sliding (>= 3 mm/s)"}},
      {"speed", {0, 0.5, 3, 10, 30, 60, 100, 150, inf}, {}},
      {"load", {0, 0.5, 1, 1.5, 2, 3, inf}, {}},
      {"direction", dir_edges, dir_labels},
      {"position", {0, 1, 2, 3, 4, 5, 6, 7, 8, 9},
       {"front-left", "front-centre", "front-right", "middle-left", "centre", "middle-right", "back-left", "back-centre",
        "back-right"}},
      {"time", {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10}, {}},
  };
  const std::vector<std::vector<double>*> keys = {&regime, &speed_mm, &load, &dir, &tile, &time};
  for (std::size_t d = 0; d < std::size(dims); ++d) {
    c.breakdown[dims[d].name]["normal_force_N"] = Bin(dims[d], *keys[d], res.normal_N, contact);
    c.breakdown[dims[d].name]["friction_N"] = Bin(dims[d], *keys[d], res.friction_N, d <= 1 ? moving : sliding);
    if (d != 0) c.breakdown[dims[d].name]["friction_ratio"] = Bin(dims[d], *keys[d], res.ratio, sliding);
  }
  if (!res.log_band.empty()) {
    const std::size_t nw = r.windows.size(), nb = r.band_lo_hz.size();
    const double db = 10 / std::log(10.0);
    // Per band: residual in dB over the windows.
    for (std::size_t b = 0; b < nb; ++b) {
      BinRow row;
      row.label = fmt::format("{:.0f}-{:.0f} Hz", r.band_lo_hz[b], r.band_hi_hz[b]);
      row.center = std::sqrt(r.band_lo_hz[b] * r.band_hi_hz[b]);
      for (std::size_t w = 0; w < nw; ++w) {
        const double x = res.log_band[w][b] * db;
        row.mean += x, row.rms += x * x, ++row.n;
      }
      if (row.n) row.mean /= row.n, row.rms = std::sqrt(row.rms / row.n);
      c.breakdown["band"]["vibration_dB"].push_back(row);
    }
    std::vector<double> wspeed(nw), wload(nw), wdir(nw), wtime(nw), wres(nw);
    std::vector<char> all(nw, 1);
    for (std::size_t w = 0; w < nw; ++w) {
      wspeed[w] = r.windows[w].speed_mps * 1e3;
      wload[w] = r.windows[w].force_N;
      wdir[w] = std::atan2(r.windows[w].dir[1], r.windows[w].dir[0]);
      if (wdir[w] >= pi - pi / 8) wdir[w] -= 2 * pi;
      wtime[w] = (r.windows[w].t_s - T0) / (T1 - T0) * 10;
      double s = 0;
      for (const double x : res.log_band[w]) s += x;
      wres[w] = s / static_cast<double>(nb) * db;
    }
    c.breakdown["speed"]["vibration_dB"] = Bin(dims[1], wspeed, wres, all);
    c.breakdown["load"]["vibration_dB"] = Bin(dims[2], wload, wres, all);
    c.breakdown["direction"]["vibration_dB"] = Bin(dims[3], wdir, wres, all);
    c.breakdown["time"]["vibration_dB"] = Bin(dims[5], wtime, wres, all);
  }
  return c;
}

// ---------------------------------------------------------------------------------------------
MeasurementSummary Summarize(const Measurement& m) {
  MeasurementSummary s;
  s.samples = static_cast<int>(m.rows.size());
  if (m.rows.size() < 2) {
    s.warnings.push_back("fewer than two rows");
    return s;
  }
  s.duration_s = m.rows.back().t_s - m.rows.front().t_s;
  std::vector<double> dt;
  for (std::size_t i = 1; i < m.rows.size(); ++i) dt.push_back(m.rows[i].t_s - m.rows[i - 1].t_s);
  auto sorted = dt;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double med = sorted[sorted.size() / 2];
  s.rate_hz = 1 / med;
  for (std::size_t i = 0; i < dt.size(); ++i) {
    s.max_gap_s = std::max(s.max_gap_s, dt[i]);
    if (dt[i] > 1.5 * med) {
      if (s.gaps < 5)
        s.warnings.push_back(fmt::format("line {}: gap of {:.4g} s ({:.1f} sample periods)", m.row_lines[i + 1], dt[i],
                                         dt[i] / med));
      ++s.gaps;
    }
  }
  const char* names[] = {"x_m", "y_m", "z_m", "vx_mps", "vy_mps", "vz_mps", "fx_N", "fy_N", "fz_N", "acc_mps2"};
  for (const auto& r : m.rows) {
    const double v[] = {r.p_m.x(), r.p_m.y(), r.p_m.z(), r.v_mps.x(), r.v_mps.y(), r.v_mps.z(),
                        r.f_N.x(), r.f_N.y(), r.f_N.z(), r.acc_mps2};
    for (int k = 0; k < (m.has_acceleration ? 10 : 9); ++k) {
      auto [it, fresh] = s.ranges.try_emplace(names[k], v[k], v[k]);
      if (!fresh) it->second.first = std::min(it->second.first, v[k]), it->second.second = std::max(it->second.second, v[k]);
    }
    s.contact_samples += r.f_N.z() > 0.02;
  }
  if (s.contact_samples == 0) s.warnings.push_back("no sample in contact (fz_N > 0.02 N)");
  if (!m.has_acceleration) s.warnings.push_back("no acc_mps2 column: the vibration channel cannot be compared");
  else if (s.rate_hz < 2000) s.warnings.push_back(fmt::format("rate {:.0f} Hz: vibration above {:.0f} Hz is not measured", s.rate_hz, s.rate_hz / 2));
  if (s.ranges.count("fz_N") && s.ranges["fz_N"].second > 10)
    s.warnings.push_back("fz_N exceeds 10 N: check the sign convention (force of the surface on the tool, +z)");
  return s;
}

}  // namespace hapticlab::modeling::wb
