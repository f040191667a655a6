#include "hapticlab/sim/sim_lab.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/biquad.hpp"
#include "truth_internal.hpp"

namespace hapticlab::sim {
namespace {

constexpr double kPi = std::numbers::pi;
using internal::Resonator;
using internal::TruthGeometry;
using internal::VibrationRms;

}  // namespace

FeatureAccumulator::FeatureAccumulator(double fr, double vr, double settle_s)
    : skip_f_(static_cast<std::uint64_t>(settle_s * fr)),
      skip_v_(static_cast<std::uint64_t>(settle_s * vr)),
      hp_(renderer::BiquadCoeffs::ButterworthHighPass(2.0, fr)),
      hpt_(renderer::BiquadCoeffs::ButterworthHighPass(2.0, fr)),
      lp_(renderer::BiquadCoeffs::ButterworthLowPass(5.0, fr)),
      hpl_(renderer::BiquadCoeffs::ButterworthHighPass(0.3, fr)),
      bhp_(renderer::BiquadCoeffs::ButterworthHighPass(40.0, vr)),
      blp_(renderer::BiquadCoeffs::ButterworthLowPass(400.0, vr)) {}

void FeatureAccumulator::AddForce(double fn, double ft, double speed, double pen) noexcept {
  const double a = hp_.Step(fn), b = hpt_.Step(ft), c = lp_.Step(hpl_.Step(fn));
  if (n_force_++ < skip_f_) return;
  fl2_ += a * a + b * b;
  pat2_ += c * c;
  fn_sum_ += fn;
  ft_sum_ += ft;
  pen_sum_ += pen;
  sp_ += speed;
  ++cnt_;
}

void FeatureAccumulator::AddVibration(double acc) noexcept {
  const double a = blp_.Step(bhp_.Step(acc));
  if (n_vib_++ < skip_v_) return;
  v2_ += a * a;
  ++vcnt_;
}

Features FeatureAccumulator::Result() const {
  Features f;
  const double m = std::max(static_cast<double>(cnt_), 1.0);
  f.fluctuation = std::log10(std::sqrt(fl2_ / m) + 1e-4);
  f.pattern = std::log10(std::sqrt(pat2_ / m) + 1e-4);
  f.friction = fn_sum_ > 0 ? ft_sum_ / fn_sum_ : 0;
  f.stiffness = std::log10(pen_sum_ > 0 ? fn_sum_ / pen_sum_ : 1.0);
  f.mean_force_N = fn_sum_ / m;
  f.mean_speed_mps = sp_ / m;
  f.vibration = std::log10(std::sqrt(v2_ / std::max(static_cast<double>(vcnt_), 1.0)) + 1e-3);
  return f;
}

Stroke DrawStroke(Rng& rng) {
  Stroke s;
  s.speed_mps = rng.Uniform(0.02, 0.15);
  s.force_N = rng.Uniform(0.5, 2.0);
  s.direction_rad = rng.Uniform(0, kPi);
  s.length_m = rng.Uniform(0.02, 0.04);
  // Centred within 5 mm of the sample's origin, so the stroke stays inside a small
  // device's workspace (the Falcon's is about 10 cm across).
  s.x0_m = rng.Uniform(-0.005, 0.005) - 0.5 * s.length_m * std::cos(s.direction_rad);
  s.y0_m = rng.Uniform(-0.005, 0.005) - 0.5 * s.length_m * std::sin(s.direction_rad);
  return s;
}

Stroke JitterStroke(const Stroke& s, Rng& rng) {
  Stroke j = s;
  j.speed_mps *= rng.Uniform(0.9, 1.1);
  j.force_N *= rng.Uniform(0.9, 1.1);
  j.direction_rad += rng.Uniform(-0.2, 0.2);
  j.x0_m = rng.Uniform(-0.005, 0.005) - 0.5 * j.length_m * std::cos(j.direction_rad);
  j.y0_m = rng.Uniform(-0.005, 0.005) - 0.5 * j.length_m * std::sin(j.direction_rad);
  return j;
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
  std::size_t at = 0;  // row-major: row i, column j
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      double v, gx, gy;
      geo.Macro(j * pitch, i * pitch, &v, &gx, &gy);
      h[at++] = static_cast<float>(v + geo.bound());
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

namespace {

void Number(const toml::table& t, const std::string& path, const std::string& pre, const char* key,
            double* out, double lo, double hi, Diagnostics& diag) {
  const toml::node* n = t.get(key);
  if (!n) return;
  auto v = n->value<double>();
  if (!v || !(*v >= lo && *v <= hi))
    diag.Add(path, static_cast<int>(n->source().begin.line), pre + "." + key,
             fmt::format("expected a number in [{}, {}]", lo, hi));
  else
    *out = *v;
}

void CheckKeys(const toml::table& t, const std::string& path, const std::string& pre,
               std::initializer_list<const char*> known, Diagnostics& diag) {
  for (const auto& [k, v] : t)
    if (std::find(known.begin(), known.end(), k.str()) == known.end())
      diag.Add(path, static_cast<int>(v.source().begin.line), pre + "." + std::string(k.str()),
               "unknown key (a typo?)");
}

// Per-criterion keys; `bias_sd` is the older name of offset_sd (profiles files).
void ParseCriterion(const toml::table& t, const std::string& path, const std::string& pre,
                    Diagnostics& diag, CriterionObserver* c) {
  Number(t, path, pre, "sensitivity", &c->sensitivity, 0, 100, diag);
  Number(t, path, pre, "bias_sd", &c->offset_sd, 0, 100, diag);
  Number(t, path, pre, "offset_sd", &c->offset_sd, 0, 100, diag);
  Number(t, path, pre, "material_sd", &c->material_sd, 0, 100, diag);
  Number(t, path, pre, "method_sd", &c->method_sd, 0, 100, diag);
  Number(t, path, pre, "noise_sd", &c->noise_sd, 0, 100, diag);
}

void ParseObserverTable(const toml::table& o, const std::string& path, Diagnostics& diag,
                        ObserverParams* ob) {
  CheckKeys(o, path, "observer",
            {"upper", "lower", "range_sd", "lapse_rate", "sensitivity", "bias_sd", "offset_sd",
             "material_sd", "method_sd", "noise_sd", "scale_vibration", "scale_fluctuation",
             "scale_friction", "scale_stiffness", "scale_pattern"},
            diag);
  Number(o, path, "observer", "upper", &ob->upper, 0, 1000, diag);
  Number(o, path, "observer", "lower", &ob->lower, 0, 1000, diag);
  Number(o, path, "observer", "range_sd", &ob->range_sd, 0, 2, diag);
  Number(o, path, "observer", "lapse_rate", &ob->lapse_rate, 0, 1, diag);
  ParseCriterion(o, path, "observer", diag, &ob->defaults);
  Number(o, path, "observer", "scale_vibration", &ob->scale_vibration, 1e-3, 10, diag);
  Number(o, path, "observer", "scale_fluctuation", &ob->scale_fluctuation, 1e-3, 10, diag);
  Number(o, path, "observer", "scale_friction", &ob->scale_friction, 1e-3, 10, diag);
  Number(o, path, "observer", "scale_stiffness", &ob->scale_stiffness, 1e-3, 10, diag);
  Number(o, path, "observer", "scale_pattern", &ob->scale_pattern, 1e-3, 10, diag);
  if (const toml::node* u = o.get("upper"); u && !(ob->lower < ob->upper))
    diag.Add(path, static_cast<int>(u->source().begin.line), "observer.upper",
             "expected upper > lower");
}

}  // namespace

ObserverParams LoadObserver(const std::string& path) {
  const toml::table doc = ParseTomlFile(path, "observer file");
  Diagnostics diag;
  ObserverParams ob;
  CheckKeys(doc, path, "", {"observer", "criterion"}, diag);
  if (const toml::table* o = doc["observer"].as_table())
    ParseObserverTable(*o, path, diag, &ob);
  else
    diag.Add(path, 1, "observer", "missing [observer] table");
  if (const toml::node* cn = doc.get("criterion")) {
    const toml::table* ct = cn->as_table();
    if (!ct)
      diag.Add(path, static_cast<int>(cn->source().begin.line), "criterion",
               "expected [criterion.NAME] tables");
    static const toml::table kEmpty;
    for (const auto& [k, v] :
         ct ? *ct : kEmpty) {  // a reference: a copy would lose the source lines
      const std::string pre = "criterion." + std::string(k.str());
      const toml::table* t = v.as_table();
      if (!t) {
        diag.Add(path, static_cast<int>(v.source().begin.line), pre, "expected a table");
        continue;
      }
      CheckKeys(*t, path, pre, {"sensitivity", "offset_sd", "material_sd", "method_sd", "noise_sd"},
                diag);
      CriterionObserver c = ob.defaults;
      ParseCriterion(*t, path, pre, diag, &c);
      ob.criteria[std::string(k.str())] = c;
    }
  }
  diag.ThrowIfAny();
  return ob;
}

ProfileSet LoadProfiles(const std::string& path) {
  const toml::table doc = ParseTomlFile(path);
  Diagnostics diag;
  ProfileSet set;
  auto num = [&](const toml::table& t, const std::string& pre, const char* key, double* out,
                 double lo, double hi) { Number(t, path, pre, key, out, lo, hi, diag); };
  const toml::array* ps = doc["profile"].as_array();
  if (!ps) diag.Add(path, 1, "profile", "no [[profile]] tables");
  for (std::size_t i = 0; ps && i < ps->size(); ++i) {
    const toml::table* t = (*ps)[i].as_table();
    const std::string pre = fmt::format("profile[{}]", i);
    if (!t) continue;
    MaterialProfile p;
    p.line = static_cast<int>(t->source().begin.line);
    if (auto id = (*t)["id"].value<std::string>())
      p.id = *id;
    else
      diag.Add(path, p.line, pre + ".id", "missing; expected a string");
    for (const auto& [k, v] : *t) {
      static const char* known[] = {"id",
                                    "roughness_m",
                                    "wavelength_m",
                                    "anisotropy",
                                    "inhomogeneity",
                                    "micro_roughness_m",
                                    "stiffness_N_per_m",
                                    "hc_n",
                                    "damping",
                                    "layer_thickness_m",
                                    "mu_k",
                                    "stribeck_ratio",
                                    "stribeck_speed_mps",
                                    "load_exponent",
                                    "vibration_rms_mps2",
                                    "vibration_peak_hz",
                                    "vibration_q",
                                    "notes"};
      if (std::find(std::begin(known), std::end(known), k.str()) == std::end(known))
        diag.Add(path, static_cast<int>(v.source().begin.line), pre + "." + std::string(k.str()),
                 "unknown key (a typo?)");
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
  if (const toml::table* o = doc["observer"].as_table())
    ParseObserverTable(*o, path, diag, &set.observer);
  diag.ThrowIfAny();
  return set;
}

Observer::Observer(const ObserverParams& p, std::uint64_t seed,
                   const std::vector<std::string>& criteria)
    : p_(p), seed_(seed) {
  Rng rng(seed);
  for (const auto& c : criteria) offset_[c] = rng.Normal(0, p_.For(c).offset_sd);
  range_ = std::exp(rng.Normal(0, p_.range_sd));
}

double Observer::Effect(const char* kind, const std::string& c, const std::string& level,
                        double sd) const {
  if (sd <= 0 || level.empty()) return 0;
  Rng rng(DeriveSeed(seed_, internal::HashId(std::string(kind) + "\x1f" + c + "\x1f" + level)));
  return rng.Normal(0, sd);
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

double Observer::Rate(const std::string& c, const std::string& material, const std::string& method,
                      const Features& a, const Features& b, double lo, double hi,
                      Rng& noise) const {
  return RateDistance(c, material, method, Distance(c, a, b), lo, hi, noise);
}

double Observer::RateDistance(const std::string& c, const std::string& material,
                              const std::string& method, double d, double lo, double hi,
                              Rng& noise) const {
  const CriterionObserver& co = p_.For(c);
  const double g = co.sensitivity * d;
  const double latent = p_.lower + (p_.upper - p_.lower) * std::exp(-0.5 * g * g);
  const auto it = offset_.find(c);
  const double offset = it == offset_.end() ? 0.0 : it->second;
  const double mid = 0.5 * (lo + hi);
  // Both draws always happen, so a lapse does not shift the rest of the trial's stream.
  const double lapse = noise.Uniform(), e = noise.Normal(0, co.noise_sd), any = noise.Uniform();
  if (lapse < p_.lapse_rate) return lo + (hi - lo) * any;
  const double s = mid + range_ * (latent - mid) + offset + p_.site_offset +
                   Effect("material", c, material, co.material_sd) +
                   Effect("method", c, method, co.method_sd) + e;
  return std::clamp(s, lo, hi);
}

double Observer::ResponseTime(Rng& noise) { return std::exp(noise.Normal(std::log(4.0), 0.35)); }

}  // namespace hapticlab::sim
