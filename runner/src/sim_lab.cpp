#include "hapticlab/runner/sim_lab.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <toml++/toml.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/biquad.hpp"

namespace hapticlab::runner {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kHandMass_kg = 0.15;      // hand + stylus mass the force fluctuations shake
constexpr double kBaseStiffness = 5000;    // a real sample's stiff base (table) [N/m]
constexpr double kSettle_s = 0.25;         // features ignore the first moments of a stroke

std::uint64_t HashId(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  return h;
}

// One sinusoidal component A sin(kx x + ky y + phi).
struct Wave {
  double a, kx, ky, phi;
};

// Analytic truth geometry of a profile: macro (isotropic + directional, patch-modulated)
// and micro components. Height above the layer's mean [m] and its gradient.
class TruthGeometry {
 public:
  explicit TruthGeometry(const MaterialProfile& p) {
    Rng rng(HashId(p.id));
    const double k0 = 2 * kPi / p.wavelength_m;
    const double iso_w = (1 - p.anisotropy) * p.roughness_m / std::sqrt(6 / 2.0);
    for (int j = 0; j < 6; ++j) {
      const double k = k0 * rng.Uniform(0.7, 1.4), th = rng.Uniform(0, kPi);
      macro_.push_back({iso_w, k * std::cos(th), k * std::sin(th), rng.Uniform(0, 2 * kPi)});
    }
    const double dir = rng.Uniform(0, kPi);
    macro_.push_back({p.anisotropy * p.roughness_m * std::sqrt(2.0), k0 * std::cos(dir), k0 * std::sin(dir),
                      rng.Uniform(0, 2 * kPi)});
    beta_ = p.inhomogeneity;
    kp_ = k0 / 10;
    pp_ = rng.Uniform(0, 2 * kPi);
    // Micro-roughness at 0.25-0.5 mm: what a stylus tip still follows and a photometric
    // map at the texture's resolution smooths away; it drives 100-600 Hz vibration at
    // stroking speeds.
    for (int j = 0; j < 4; ++j) {
      const double k = 2 * kPi / rng.Uniform(0.25e-3, 0.5e-3), th = rng.Uniform(0, kPi);
      micro_.push_back({p.micro_roughness_m / std::sqrt(2.0), k * std::cos(th), k * std::sin(th), rng.Uniform(0, 2 * kPi)});
    }
    bound_ = 0;
    for (const auto& w : macro_) bound_ += std::abs(w.a);
    bound_ *= 1 + beta_;
    for (const auto& w : micro_) bound_ += std::abs(w.a);
  }
  // Macro height (what a photometric map resolves), with gradient.
  void Macro(double x, double y, double* h, double* hx, double* hy) const {
    double g = 0, gx = 0, gy = 0;
    for (const auto& w : macro_) {
      const double ph = w.kx * x + w.ky * y + w.phi;
      g += w.a * std::sin(ph);
      gx += w.a * w.kx * std::cos(ph);
      gy += w.a * w.ky * std::cos(ph);
    }
    const double m = 1 + beta_ * std::sin(kp_ * x + pp_) * std::sin(kp_ * y + 2 * pp_);
    const double mx = beta_ * kp_ * std::cos(kp_ * x + pp_) * std::sin(kp_ * y + 2 * pp_);
    const double my = beta_ * kp_ * std::sin(kp_ * x + pp_) * std::cos(kp_ * y + 2 * pp_);
    *h = g * m;
    *hx = gx * m + g * mx;
    *hy = gy * m + g * my;
  }
  // Full height with micro-roughness, its gradient, and the second derivative along (ux, uy)
  // of the micro part (the stylus acceleration it imposes at speed 1 m/s).
  void Full(double x, double y, double ux, double uy, double* h, double* hx, double* hy, double* micro_dd) const {
    Macro(x, y, h, hx, hy);
    double dd = 0;
    for (const auto& w : micro_) {
      const double ph = w.kx * x + w.ky * y + w.phi;
      *h += w.a * std::sin(ph);
      *hx += w.a * w.kx * std::cos(ph);
      *hy += w.a * w.ky * std::cos(ph);
      const double ku = w.kx * ux + w.ky * uy;
      dd -= w.a * ku * ku * std::sin(ph);
    }
    *micro_dd = dd;
  }
  double bound() const { return bound_; }

 private:
  std::vector<Wave> macro_, micro_;
  double beta_ = 0, kp_ = 1, pp_ = 0, bound_ = 0;
};

// Contact vibration level of the truth at (speed, load) [m/s^2 RMS].
double VibrationRms(const MaterialProfile& p, double v, double f) {
  return p.vibration_rms_mps2 * std::pow(std::max(v, 0.0) / 0.08, 0.8) * std::pow(std::max(f, 0.0) / 1.2, 0.5);
}

// AR(2) resonator at f0 with quality Q at rate fs: c1, c2 and the stationary variance of its
// output for unit-variance innovations.
void Resonator(double f0, double q, double fs, double* c1, double* c2, double* var) {
  const double w = 2 * kPi * f0 / fs, r = std::exp(-kPi * f0 / (q * fs));
  *c1 = 2 * r * std::cos(w);
  *c2 = -r * r;
  *var = (1 - *c2) / ((1 + *c2) * ((1 - *c2) * (1 - *c2) - *c1 * *c1));
}

// The hand: integral control of the normal force by the tool height, and the stroke path.
struct Hand {
  Stroke s;
  double z_m = 0, gain = 0;
  double ux = 1, uy = 0;
  void Init(const Stroke& st, double z0, double stiffness) {
    s = st;
    z_m = z0;
    gain = 20.0 / std::max(stiffness, 50.0);  // ~20 rad/s force loop closed by the hand
    ux = std::cos(s.direction_rad);
    uy = std::sin(s.direction_rad);
  }
  // Position along the stroke at t: a triangle wave of constant speed.
  void At(double t, double* x, double* y, double* vx, double* vy) const {
    const double period = 2 * s.length_m / s.speed_mps;
    const double ph = std::fmod(t, period) / period;
    const double d = ph < 0.5 ? 2 * ph * s.length_m : (2 - 2 * ph) * s.length_m;
    const double v = ph < 0.5 ? s.speed_mps : -s.speed_mps;
    *x = s.x0_m + d * ux;
    *y = s.y0_m + d * uy;
    *vx = v * ux;
    *vy = v * uy;
  }
  double Step(double fn, double dt) {
    const double dz = -gain * (s.force_N - fn) * dt;
    z_m += dz;
    return dz / dt;
  }
};

// The stylus acceleration that force fluctuations cause: the force above 40 Hz (which the
// hand does not resist) on the hand-tool mass, along the stroke and the normal.
class ForceShake {
 public:
  explicit ForceShake(double fr) {
    for (auto& b : hp_) b.SetCoeffs(renderer::BiquadCoeffs::ButterworthHighPass(40.0, fr));
  }
  double Step(const Eigen::Vector3d& f, double ux, double uy) {
    const double ax = hp_[0].Step(f.x()), ay = hp_[1].Step(f.y()), az = hp_[2].Step(f.z());
    return (ax * ux + ay * uy + az) / kHandMass_kg;
  }

 private:
  std::array<renderer::Biquad, 3> hp_;
};

// Feature extraction, identical for real and virtual interactions.
Features Extract(const Interaction& in, const std::vector<double>& penetration) {
  Features f;
  const double fr = in.force_rate_hz, vr = in.vibration_rate_hz;
  const std::size_t n = in.force.size() / 15;
  const auto skip = static_cast<std::size_t>(kSettle_s * fr);
  renderer::Biquad hp(renderer::BiquadCoeffs::ButterworthHighPass(2.0, fr));
  renderer::Biquad hpt(renderer::BiquadCoeffs::ButterworthHighPass(2.0, fr));
  renderer::Biquad lp(renderer::BiquadCoeffs::ButterworthLowPass(5.0, fr));
  renderer::Biquad hpl(renderer::BiquadCoeffs::ButterworthHighPass(0.3, fr));
  double fl2 = 0, pat2 = 0, fn_sum = 0, ft_sum = 0, pen_sum = 0, sp = 0;
  std::size_t cnt = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const float* r = &in.force[i * 15];
    const double fn = r[11], ft = std::hypot(r[9], r[10]);
    const double a = hp.Step(fn), b = hpt.Step(ft), c = lp.Step(hpl.Step(fn));
    if (i < skip) continue;
    fl2 += a * a + b * b;
    pat2 += c * c;
    fn_sum += fn;
    ft_sum += ft;
    pen_sum += penetration[i];
    sp += r[13];
    ++cnt;
  }
  const double m = std::max(static_cast<double>(cnt), 1.0);
  f.fluctuation = std::log10(std::sqrt(fl2 / m) + 1e-4);
  f.pattern = std::log10(std::sqrt(pat2 / m) + 1e-4);
  f.friction = fn_sum > 0 ? ft_sum / fn_sum : 0;
  f.stiffness = std::log10(pen_sum > 0 ? fn_sum / pen_sum : 1.0);
  f.mean_force_N = fn_sum / m;
  f.mean_speed_mps = sp / m;
  renderer::Biquad bhp(renderer::BiquadCoeffs::ButterworthHighPass(40.0, vr));
  renderer::Biquad blp(renderer::BiquadCoeffs::ButterworthLowPass(400.0, vr));
  double v2 = 0;
  std::size_t vc = 0;
  const auto vskip = static_cast<std::size_t>(kSettle_s * vr);
  for (std::size_t i = 0; i < in.vibration.size(); ++i) {
    const double a = blp.Step(bhp.Step(in.vibration[i]));
    if (i < vskip) continue;
    v2 += a * a;
    ++vc;
  }
  f.vibration = std::log10(std::sqrt(v2 / std::max(static_cast<double>(vc), 1.0)) + 1e-3);
  return f;
}

void PushForce(std::vector<float>& out, double x, double y, double z, double vx, double vy, double vz,
               const Eigen::Vector3d& raw, const Eigen::Vector3d& cmd, double fn, double speed, bool fault) {
  const double v[15] = {x, y, z, vx, vy, vz, raw.x(), raw.y(), raw.z(), cmd.x(), cmd.y(), cmd.z(), fn, speed, fault ? 1.0 : 0.0};
  for (double d : v) out.push_back(static_cast<float>(d));
}

}  // namespace

Stroke DrawStroke(Rng& rng) {
  Stroke s;
  s.speed_mps = rng.Uniform(0.02, 0.15);
  s.force_N = rng.Uniform(0.5, 2.0);
  s.direction_rad = rng.Uniform(0, kPi);
  s.x0_m = rng.Uniform(0, 0.05);
  s.y0_m = rng.Uniform(0, 0.05);
  s.length_m = rng.Uniform(0.03, 0.05);
  return s;
}

Stroke JitterStroke(const Stroke& s, Rng& rng) {
  Stroke j = s;
  j.speed_mps *= rng.Uniform(0.9, 1.1);
  j.force_N *= rng.Uniform(0.9, 1.1);
  j.direction_rad += rng.Uniform(-0.2, 0.2);
  j.x0_m = rng.Uniform(0, 0.05);
  j.y0_m = rng.Uniform(0, 0.05);
  return j;
}

Interaction StrokeReal(const MaterialProfile& p, const Stroke& s, double duration_s, std::uint64_t seed) {
  Interaction out;
  const double fr = out.force_rate_hz, vr = out.vibration_rate_hz, dt = 1.0 / fr;
  const int per = static_cast<int>(vr / fr);
  const TruthGeometry geo(p);
  const double offset = geo.bound();  // keeps the texture top above the layer's floor
  Rng rng(seed);
  double c1, c2, var;
  Resonator(p.vibration_peak_hz, p.vibration_q, vr, &c1, &c2, &var);
  double a1 = 0, a2 = 0;
  Hand hand;
  hand.Init(s, p.layer_thickness_m + offset, p.stiffness_N_per_m);
  ForceShake shake(fr);
  const auto n = static_cast<std::size_t>(duration_s * fr);
  out.force.reserve(n * 15);
  out.vibration.reserve(n * static_cast<std::size_t>(per));
  std::vector<double> pen;
  pen.reserve(n);
  double vz = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * dt;
    double x, y, vx, vy;
    hand.At(t, &x, &y, &vx, &vy);
    const double speed = std::hypot(vx, vy);
    const double ux = speed > 0 ? vx / speed : 0, uy = speed > 0 ? vy / speed : 0;
    double h, hx, hy, micro_dd;
    geo.Full(x, y, ux, uy, &h, &hx, &hy, &micro_dd);
    const double top = p.layer_thickness_m + offset + h;
    const double z = hand.z_m;
    double d_t = 0, d_rate = 0;
    if (z < 0) {
      d_t = top;
      d_rate = hx * vx + hy * vy;
    } else if (z < top) {
      d_t = top - z;
      d_rate = hx * vx + hy * vy - vz;
    }
    const double dn = std::pow(std::max(d_t, 0.0), p.hc_n);
    const double f_layer = std::max(0.0, p.stiffness_N_per_m * dn + p.damping * dn * d_rate);
    const double f_base = z < 0 ? kBaseStiffness * -z : 0.0;
    const double fn = f_layer + f_base;
    // Real surfaces push along their true normal; friction with Stribeck and load exponent.
    const Eigen::Vector3d normal = Eigen::Vector3d(-hx, -hy, 1.0).normalized();
    const double mu = p.mu_k * (1 + (p.stribeck_ratio - 1) * std::exp(-std::pow(speed / p.stribeck_speed_mps, 2)));
    const double ff = fn > 0 ? mu * std::pow(fn, p.load_exponent) * std::tanh(speed / 1e-3) : 0.0;
    Eigen::Vector3d f = fn * normal;
    f.x() -= ff * ux;
    f.y() -= ff * uy;
    PushForce(out.force, x, y, z, vx, vy, vz, f, f, fn, speed, false);
    pen.push_back(d_t + std::max(0.0, -z));
    // Felt acceleration: contact vibration + micro-geometry + force fluctuation / hand mass.
    const bool contact = fn > 1e-3;
    const double rms = contact ? VibrationRms(p, speed, fn) : 0.0;
    const double a_force = shake.Step(f, ux, uy);
    for (int j = 0; j < per; ++j) {
      const double a = c1 * a1 + c2 * a2 + rms / std::sqrt(var) * rng.Normal();
      a2 = a1;
      a1 = a;
      out.vibration.push_back(static_cast<float>(a + (contact ? micro_dd * speed * speed : 0.0) + a_force));
    }
    vz = hand.Step(fn, dt);
  }
  out.features = Extract(out, pen);
  return out;
}

Interaction StrokeVirtual(const renderer::MaterialModel& m, const renderer::RenderOptions& o, const Stroke& s,
                          double duration_s) {
  Interaction out;
  out.force_rate_hz = o.force_rate_hz;
  out.vibration_rate_hz = o.vibration_rate_hz;
  const double fr = o.force_rate_hz, dt = 1.0 / fr;
  const int per = static_cast<int>(std::lround(o.vibration_rate_hz / fr));
  renderer::HybridRenderer r(m, o);
  Hand hand;
  const double top0 = m.contact.layer_thickness_m + (m.geometry->max_m() - m.geometry->min_m());
  hand.Init(s, top0, m.contact.texture.K + 0.5 * o.device_max_stiffness_N_per_m);
  ForceShake shake(fr);
  const auto n = static_cast<std::size_t>(duration_s * fr);
  out.force.reserve(n * 15);
  out.vibration.reserve(n * static_cast<std::size_t>(per));
  std::vector<double> pen;
  pen.reserve(n);
  double vz = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * dt;
    double x, y, vx, vy;
    hand.At(t, &x, &y, &vx, &vy);
    renderer::DeviceSample ds;
    ds.state.p_m = {x, y, hand.z_m};
    ds.state.v_mps = {vx, vy, vz};
    ds.t_s = t;
    const auto cmd = r.ForceTick(ds, t);
    if (cmd.fault) ++out.faults;
    const double fn = cmd.force_N.z();
    PushForce(out.force, x, y, hand.z_m, vx, vy, vz, cmd.raw.force_N, cmd.force_N, std::max(fn, 0.0),
              cmd.raw.tangential_speed_mps, cmd.fault);
    pen.push_back(cmd.raw.penetration_m);
    const double speed = std::hypot(vx, vy);
    const double a_force = shake.Step(cmd.force_N, speed > 0 ? vx / speed : 0, speed > 0 ? vy / speed : 0);
    for (int j = 0; j < per; ++j) out.vibration.push_back(static_cast<float>(r.VibrationTick() + a_force));
    vz = hand.Step(std::max(fn, 0.0), dt);
  }
  out.features = Extract(out, pen);
  return out;
}

renderer::MaterialModel PlaceholderModel(const MaterialProfile& p) {
  renderer::MaterialModel m;
  m.name = p.id + " (placeholder)";
  m.effects = {"coulomb", "viscous", "dahl", "hc-damping"};
  m.contact.texture = {p.stiffness_N_per_m, p.damping, p.hc_n};
  m.contact.base = {0, 0, 1};  // half the device's maximum stiffness (ch. V)
  const TruthGeometry geo(p);
  m.contact.layer_thickness_m = p.layer_thickness_m;
  m.friction = {2000, p.mu_k, 0.05};
  // The macro geometry as a photometric map would see it: wavelength / 20 pitch, 256 x 256.
  const int n = 256;
  const double pitch = p.wavelength_m / 20;
  std::vector<float> h(static_cast<std::size_t>(n * n));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      double v, gx, gy;
      geo.Macro(j * pitch, i * pitch, &v, &gx, &gy);
      h[static_cast<std::size_t>(i * n + j)] = static_cast<float>(v + geo.bound());
    }
  m.geometry = std::make_shared<renderer::HeightMap>(n, n, pitch, std::move(h));
  // AR bank on the thesis's 3 x 3 grid: the truth resonance at the 2 kHz model rate, with
  // the variance that reproduces the truth's contact-vibration level at each condition.
  auto& b = m.vibration;
  b.sample_rate_hz = 2000;
  b.grid_speeds_mps = {0.04, 0.08, 0.12};
  b.grid_forces_N = {0.54, 1.18, 1.91};
  double c1, c2, var;
  Resonator(std::min(p.vibration_peak_hz, 900.0), p.vibration_q, b.sample_rate_hz, &c1, &c2, &var);
  for (double v : b.grid_speeds_mps)
    for (double f : b.grid_forces_N) {
      renderer::ArCell c;
      c.speed_mps = v;
      c.force_N = f;
      c.coeffs = {c1, c2};
      c.lsf = renderer::ArToLsf(c.coeffs);
      c.variance = std::pow(VibrationRms(p, v, f), 2) / var;
      b.cells.push_back(c);
    }
  m.hybrid_cutoff_hz = 100;
  return m;
}

ProfileSet LoadProfiles(const std::string& path) {
  toml::table doc;
  try {
    doc = toml::parse(ReadTomlFile(path), path);
  } catch (const toml::parse_error& e) {
    throw InputError(path, static_cast<int>(e.source().begin.line), "", std::string(e.description()));
  }
  Diagnostics diag;
  ProfileSet set;
  auto num = [&](const toml::table& t, const std::string& pre, const char* key, double* out, double lo, double hi) {
    const toml::node* n = t.get(key);
    if (!n) return;
    auto v = n->value<double>();
    if (!v || !(*v >= lo && *v <= hi))
      diag.Add(path, static_cast<int>(n->source().begin.line), pre + "." + key, fmt::format("expected a number in [{}, {}]", lo, hi));
    else *out = *v;
  };
  const toml::array* ps = doc["profile"].as_array();
  if (!ps) diag.Add(path, 1, "profile", "no [[profile]] tables");
  for (std::size_t i = 0; ps && i < ps->size(); ++i) {
    const toml::table* t = (*ps)[i].as_table();
    const std::string pre = fmt::format("profile[{}]", i);
    if (!t) continue;
    MaterialProfile p;
    p.line = static_cast<int>(t->source().begin.line);
    if (auto id = (*t)["id"].value<std::string>()) p.id = *id;
    else diag.Add(path, p.line, pre + ".id", "missing; expected a string");
    for (const auto& [k, v] : *t) {
      static const char* known[] = {"id", "roughness_m", "wavelength_m", "anisotropy", "inhomogeneity", "micro_roughness_m",
                                    "stiffness_N_per_m", "hc_n", "damping", "layer_thickness_m", "mu_k", "stribeck_ratio",
                                    "stribeck_speed_mps", "load_exponent", "vibration_rms_mps2", "vibration_peak_hz",
                                    "vibration_q", "notes"};
      if (std::none_of(std::begin(known), std::end(known), [&](const char* x) { return k.str() == x; }))
        diag.Add(path, static_cast<int>(v.source().begin.line), pre + "." + std::string(k.str()), "unknown key (a typo?)");
    }
    num(*t, pre, "roughness_m", &p.roughness_m, 0, 1e-3);
    num(*t, pre, "wavelength_m", &p.wavelength_m, 1e-5, 0.05);
    num(*t, pre, "anisotropy", &p.anisotropy, 0, 1);
    num(*t, pre, "inhomogeneity", &p.inhomogeneity, 0, 0.95);
    num(*t, pre, "micro_roughness_m", &p.micro_roughness_m, 0, 1e-4);
    num(*t, pre, "stiffness_N_per_m", &p.stiffness_N_per_m, 1, 1e6);
    num(*t, pre, "hc_n", &p.hc_n, 1, 2);
    num(*t, pre, "damping", &p.damping, 0, 1e4);
    num(*t, pre, "layer_thickness_m", &p.layer_thickness_m, 1e-5, 0.02);
    num(*t, pre, "mu_k", &p.mu_k, 0, 3);
    num(*t, pre, "stribeck_ratio", &p.stribeck_ratio, 1, 5);
    num(*t, pre, "stribeck_speed_mps", &p.stribeck_speed_mps, 1e-4, 1);
    num(*t, pre, "load_exponent", &p.load_exponent, 0.5, 1.5);
    num(*t, pre, "vibration_rms_mps2", &p.vibration_rms_mps2, 0, 100);
    num(*t, pre, "vibration_peak_hz", &p.vibration_peak_hz, 20, 1000);
    num(*t, pre, "vibration_q", &p.vibration_q, 0.5, 50);
    if (!p.id.empty() && !set.profiles.emplace(p.id, p).second)
      diag.Add(path, p.line, pre + ".id", "duplicate profile '" + p.id + "'");
  }
  if (const toml::table* o = doc["observer"].as_table()) {
    auto& ob = set.observer;
    num(*o, "observer", "upper", &ob.upper, 0, 1000);
    num(*o, "observer", "lower", &ob.lower, 0, 1000);
    num(*o, "observer", "bias_sd", &ob.bias_sd, 0, 100);
    num(*o, "observer", "noise_sd", &ob.noise_sd, 0, 100);
    for (const auto& [k, v] : *o) {
      static const char* known[] = {"upper", "lower", "bias_sd", "noise_sd", "scale_vibration", "scale_fluctuation",
                                    "scale_friction", "scale_stiffness", "scale_pattern"};
      if (std::none_of(std::begin(known), std::end(known), [&](const char* x) { return k.str() == x; }))
        diag.Add(path, static_cast<int>(v.source().begin.line), "observer." + std::string(k.str()), "unknown key (a typo?)");
    }
    num(*o, "observer", "scale_vibration", &ob.scale_vibration, 1e-3, 10);
    num(*o, "observer", "scale_fluctuation", &ob.scale_fluctuation, 1e-3, 10);
    num(*o, "observer", "scale_friction", &ob.scale_friction, 1e-3, 10);
    num(*o, "observer", "scale_stiffness", &ob.scale_stiffness, 1e-3, 10);
    num(*o, "observer", "scale_pattern", &ob.scale_pattern, 1e-3, 10);
  }
  diag.ThrowIfAny();
  return set;
}

Observer::Observer(const ObserverParams& p, std::uint64_t seed, const std::vector<std::string>& criteria) : p_(p) {
  Rng rng(seed);
  for (const auto& c : criteria) bias_[c] = rng.Normal(0, p_.bias_sd);
}

double Observer::Distance(const std::string& c, const Features& a, const Features& b) const {
  const double dv = (a.vibration - b.vibration) / p_.scale_vibration;
  const double dr = (a.fluctuation - b.fluctuation) / p_.scale_fluctuation;
  const double dm = (a.friction - b.friction) / p_.scale_friction;
  const double dk = (a.stiffness - b.stiffness) / p_.scale_stiffness;
  const double dp = (a.pattern - b.pattern) / p_.scale_pattern;
  const double rough = std::sqrt((dv * dv + dr * dr) / 2);
  const double geometry = std::sqrt((dr * dr + dp * dp) / 2);
  if (c == "roughness") return rough;
  if (c == "friction") return std::abs(dm);
  if (c == "hardness" || c == "stiffness") return std::abs(dk);
  if (c == "geometry") return geometry;
  // "overall" and any other criterion: all cues together.
  return std::sqrt((rough * rough + dm * dm + dk * dk + geometry * geometry) / 4);
}

double Observer::Rate(const std::string& c, const Features& a, const Features& b, double lo, double hi,
                      Rng& noise) const {
  const double d = Distance(c, a, b);
  const auto it = bias_.find(c);
  const double bias = it == bias_.end() ? 0.0 : it->second;
  const double s = p_.lower + (p_.upper - p_.lower) * std::exp(-0.5 * d * d) + bias + noise.Normal(0, p_.noise_sd);
  return std::clamp(s, lo, hi);
}

double Observer::ResponseTime(Rng& noise) { return std::exp(noise.Normal(std::log(4.0), 0.35)); }

}  // namespace hapticlab::runner
