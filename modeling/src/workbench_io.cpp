// Workbench model files: a renderer material TOML plus a [workbench] table with every
// effect's parameters and the vibration coefficients.

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/material.hpp"

namespace hapticlab::modeling::wb {
namespace {

constexpr double kMm = 1e-3;
constexpr int kBankOrder = 16;

// ln-key knots "knot0", "knot1", ... of a vibration axis effect, exponentiated.
std::vector<double> ExpKnots(const Model& m, std::string_view e) {
  std::vector<double> out;
  const auto& ps = m.params.at(std::string(e));
  for (int k = 0;; ++k) {
    const auto it = ps.find(fmt::format("{}{}", kKnotPrefix, k));
    if (it == ps.end()) break;
    out.push_back(std::exp(it->second));
  }
  return out;
}

// Autocorrelation of a piecewise-constant band spectrum (power per bin as the workbench
// measures it) at `fs`, then Levinson-Durbin: the AR model whose spectrum matches it.
renderer::ArCell BandsToAr(const std::vector<double>& edges, const std::vector<double>& power,
                           double fs) {
  const int M = 4096;  // frequency grid over [0, fs/2]
  std::vector<double> S(M + 1);
  for (int j = 0; j <= M; ++j) {
    const double f = 0.5 * fs * j / M;
    // Outside the analysed bands the outermost band continues: a cliff would cost the
    // all-pole fit its resolution where it matters.
    double p = f < edges.front() ? power.front() : power.back();
    for (std::size_t b = 0; b + 1 < edges.size(); ++b)
      if (f >= edges[b] && f < edges[b + 1]) p = power[b];
    S[j] = p;
  }
  std::vector<double> R(kBankOrder + 1);
  for (int k = 0; k <= kBankOrder; ++k) {
    double s = 0;
    for (int j = 0; j <= M; ++j) {
      const double w = (j == 0 || j == M) ? 0.5 : 1.0;
      s += w * S[j] * std::cos(std::numbers::pi * j * k / M);
    }
    R[k] = s / M;
  }
  std::vector<double> a(kBankOrder + 1, 0), tmp;
  a[0] = 1;
  double err = R[0];
  for (int m = 1; m <= kBankOrder; ++m) {
    double acc = R[m];
    for (int i = 1; i < m; ++i) acc += a[i] * R[m - i];
    const double k = -acc / err;
    tmp = a;
    for (int i = 1; i < m; ++i) a[i] = tmp[i] + k * tmp[m - i];
    a[m] = k;
    err *= 1 - k * k;
  }
  renderer::ArCell c;
  for (int i = 1; i <= kBankOrder; ++i) c.coeffs.push_back(-a[i]);
  c.variance = err;
  return c;
}

// The renderer's part of a workbench model: its contact law and Dahl friction.
renderer::MaterialModel RendererMaterial(const Model& m, const std::string& path) {
  renderer::MaterialModel mm;
  mm.name = m.name.empty() ? std::filesystem::path(path).stem().string() : m.name;
  mm.effects = m.effects;
  // Without dahl the renderer's bristle is stiff enough to act as ideal Coulomb friction.
  const auto cp = ContactParameters::From(m, /*no_dahl_kappa_N_per_m=*/1e6);
  mm.contact.texture.K = cp.K_N_per_m_pow_n();
  mm.contact.texture.B = cp.B_Ns_per_m_pow_n_plus_1();
  mm.contact.texture.n = cp.n;
  mm.contact.base_model = renderer::BaseModel::kLinear;
  if (m.Has(effect::kBaseLayer)) {
    mm.contact.base = {m.Get(key::kBaseK_N_per_m, 0), 0, 1};
    mm.contact.layer_thickness_m = m.Get(key::kLayer_m, 0);
  } else {
    // No base was felt: the layer is thicker than any measured penetration.
    mm.contact.base = {0, 0, 1};
    mm.contact.layer_thickness_m = 0.005;
  }
  mm.friction.mu_k = cp.mu_k;
  mm.friction.kappa_N_per_m = cp.kappa_N_per_m;
  mm.friction.mu_b_Ns_per_m = cp.mu_b_Ns_per_m;
  return mm;
}

// The renderer's grid needs two values per axis: a single speed or force is repeated a step
// away (twice it), its cells copied.
void WidenSingleKnotGrid(renderer::VibrationBank* v) {
  const std::size_t ns = v->grid_speeds_mps.size(), nf = v->grid_forces_N.size();
  if (ns >= 2 && nf >= 2) return;
  auto widen = [](std::vector<double>& x) {
    if (x.size() == 1) x.push_back(x[0] * 2);
  };
  const auto cells = v->cells;
  widen(v->grid_speeds_mps);
  widen(v->grid_forces_N);
  v->cells.clear();
  for (std::size_t i = 0; i < v->grid_speeds_mps.size(); ++i)
    for (std::size_t j = 0; j < v->grid_forces_N.size(); ++j) {
      auto c = cells[std::min(i, ns - 1) * nf + std::min(j, nf - 1)];
      c.speed_mps = v->grid_speeds_mps[i];
      c.force_N = v->grid_forces_N[j];
      v->cells.push_back(c);
    }
}

// The band model as the renderer's AR bank: one cell per knot of the speed and force effects
// (direction averaged out), at the measurement's acceleration rate.
void AddArBank(const Model& m, const Replay& r, renderer::MaterialModel* mm) {
  std::vector<double> speeds{0.05}, forces{1.0};
  if (m.Has(effect::kVibrationSpeed)) speeds = ExpKnots(m, effect::kVibrationSpeed);
  if (m.Has(effect::kVibrationForce)) forces = ExpKnots(m, effect::kVibrationForce);
  Replay grid = r;
  grid.windows.clear();
  for (const double v : speeds)
    for (const double f : forces) {
      Replay::Window w{};
      w.speed_mps = v;
      w.force_N = f;
      w.band_power.assign(r.band_lo_hz.size(), 1);
      grid.windows.push_back(w);
    }
  const auto p = Predict(m, grid);
  auto& vib = mm->vibration;
  vib.sample_rate_hz = r.acc_rate_hz;
  vib.grid_speeds_mps = speeds;
  vib.grid_forces_N = forces;
  for (std::size_t k = 0; k < grid.windows.size(); ++k) {
    auto c = BandsToAr(m.band_edges_hz, p.band_power[k], r.acc_rate_hz);
    c.speed_mps = grid.windows[k].speed_mps;
    c.force_N = grid.windows[k].force_N;
    vib.cells.push_back(std::move(c));
  }
  WidenSingleKnotGrid(&vib);
}

// A list of numbers as TOML, each to 17 digits.
std::string TomlNumbers(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += fmt::format("{}{:.17g}", i ? ", " : "", v[i]);
  return s + "]";
}

// The [workbench] table: version, band edges, every listed effect's parameters and the
// vibration coefficients.
std::string WorkbenchToml(const Model& m) {
  std::string s = "\n[workbench]\nversion = 1\n";
  if (!m.band_edges_hz.empty()) s += "band_edges_hz = " + TomlNumbers(m.band_edges_hz) + "\n";
  for (const auto& [e, ps] : m.params) {
    if (e != effect::kCore && !m.Has(e)) continue;
    s += fmt::format("\n[workbench.params.{}]\n", e);
    for (const auto& [k, v] : ps) s += fmt::format("{} = {:.17g}\n", k, v);
  }
  if (!m.coef.empty()) {
    s += "\n[workbench.coef]  # ln band power: intercepts (core) and bands x columns per effect\n";
    for (const auto& [e, v] : m.coef) s += fmt::format("{} = {}\n", e, TomlNumbers(v));
  }
  return s;
}

// Never leave a file this program would refuse to read: write beside the target, read it back
// with LoadModel (the renderer's checks and the workbench's), and only then move it into
// place. A model that does not read back is this program's error, not the user's input.
void WriteReadBack(const std::string& text, const std::string& path) {
  const std::string tmp = path + ".writing";
  WriteTextFile(tmp, text);  // std::runtime_error (exit 1) when the file cannot be written
  try {
    LoadModel(tmp);
  } catch (const InputError& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw PreconditionError(fmt::format(
        "the fitted model would not read back, so {} was not written: {}", path, e.what()));
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(path + ": cannot write (the model could not be moved into place)");
  }
}

// The source line of a TOML node (0 where there is none).
int LineOf(const toml::node* n) { return n ? static_cast<int>(n->source().begin.line) : 0; }

// The material's effects that the catalogue has into m->effects; each other is an error.
void ReadEffects(const renderer::MaterialModel& mm, const toml::table& doc, const std::string& path,
                 Diagnostics* diag, Model* m) {
  const toml::node* effects_node = doc.get("effects");
  for (std::size_t i = 0; i < mm.effects.size(); ++i) {
    const auto& e = mm.effects[i];
    const toml::node* at =
        effects_node && effects_node->as_array() ? effects_node->as_array()->get(i) : effects_node;
    if (!FindEffect(e)) {
      diag->Add(path, LineOf(at), "effects",
                fmt::format("unknown effect '{}'; expected one of: {}", e, CatalogueNames()));
      continue;
    }
    m->effects.push_back(e);
  }
}

// A renderer material (no [workbench] table): its contact and friction tables are the
// baseline's parameters, its effects (or those its tables imply) the model's.
void BaselineOfMaterial(const renderer::MaterialModel& mm, const toml::table& doc,
                        const std::string& path, Diagnostics* diag, Model* m) {
  if (m->effects.empty()) m->effects = ContactEffectsOf(mm);
  const double scale = std::pow(kMm, mm.contact.texture.n);
  const ContactParameters cp{.K1mm_N = mm.contact.texture.K * scale,
                             .n = mm.contact.texture.n,
                             .B1mm_Ns_per_m = mm.contact.texture.B * scale,
                             .mu_k = mm.friction.mu_k,
                             .mu_b_Ns_per_m = mm.friction.mu_b_Ns_per_m,
                             .kappa_N_per_m = mm.friction.kappa_N_per_m};
  cp.ToModel(m);
  // Vibration effects of a renderer material are its AR bank, not the workbench's band
  // model: they are kept and have no coefficients until `hapticlab fit` fits them.
  for (const auto& e : m->effects)
    if (!m->params.count(e) && FindEffect(e)->channel() != Channel::kVibration)
      diag->Add(path, LineOf(doc.get("effects")), "effects",
                fmt::format("effect '{}' has no parameters in a renderer material; a workbench "
                            "fit with the effect added gives them",
                            e));
  for (auto it = m->params.begin(); it != m->params.end();)
    it = (it->first == effect::kCore || m->Has(it->first)) ? std::next(it) : m->params.erase(it);
}

// [workbench] version and band_edges_hz (ascending).
void ReadHeader(const toml::table& wb, const std::string& path, Diagnostics* diag, Model* m) {
  if (const auto* v = wb["version"].as_integer(); !v || v->get() != 1)
    diag->Add(path, LineOf(&wb), "workbench.version", "expected version = 1");
  const auto* a = wb["band_edges_hz"].as_array();
  if (!a) return;
  for (const auto& x : *a) {
    const auto d = x.value<double>();
    if (!d || (!m->band_edges_hz.empty() && *d <= m->band_edges_hz.back()))
      diag->Add(path, LineOf(&x), "workbench.band_edges_hz", "expected ascending numbers [Hz]");
    else
      m->band_edges_hz.push_back(*d);
  }
}

// [workbench.params.<e>] of one effect: its known parameters, finite numbers.
void ReadEffectParams(const std::string& e, const toml::table& t, const std::string& path,
                      Diagnostics* diag, Model* m) {
  std::set<std::string> known;
  if (e == effect::kCore)
    known.emplace(key::kK1mm_N.name);
  else
    for (const auto& spec : FindEffect(e)->Params(Replay{})) known.insert(spec.name);
  for (const auto& [pk, pv] : t) {
    const auto d = pv.value<double>();
    const std::string field = fmt::format("workbench.params.{}.{}", e, pk.str());
    if (!known.count(std::string(pk.str())))
      diag->Add(path, LineOf(&pv), field,
                fmt::format("unknown parameter; {} has: {}", e, fmt::join(known, ", ")));
    else if (!d || !std::isfinite(*d))
      diag->Add(path, LineOf(&pv), field, "expected a finite number");
    else
      m->params[e][std::string(pk.str())] = *d;
  }
}

// [workbench.params]: a table per listed effect (and core, with its K1mm_N); every listed
// effect but a vibration one needs its parameters.
void ReadParams(const toml::table& wb, const std::string& path, Diagnostics* diag, Model* m) {
  if (const auto* ps = wb["params"].as_table()) {
    for (const auto& [k, v] : *ps) {
      const std::string e(k.str());
      const toml::table* t = v.as_table();
      if (e != effect::kCore && !m->Has(e))
        diag->Add(path, LineOf(&v), "workbench.params." + e,
                  "parameters of an effect not listed in effects = [...]");
      else if (!t)
        diag->Add(path, LineOf(&v), "workbench.params." + e, "expected a table of numbers");
      else
        ReadEffectParams(e, *t, path, diag, m);
    }
  }
  const std::string core(effect::kCore);
  if (!m->params.count(core) || !m->params[core].count(std::string(key::kK1mm_N.name)))
    diag->Add(path, LineOf(&wb), fmt::format("workbench.params.{}.{}", core, key::kK1mm_N.name),
              "missing: the normal force at 1 mm penetration [N]");
  for (const auto& e : m->effects)
    if (!m->params.count(e) && FindEffect(e)->channel() != Channel::kVibration)
      diag->Add(path, LineOf(&wb), "workbench.params." + e,
                "missing: every listed effect needs its parameters");
}

// [workbench.coef]: per band (core, the range bounds) or bands x columns of a listed vibration
// effect.
void ReadCoefficients(const toml::table& wb, const std::string& path, Diagnostics* diag, Model* m) {
  const auto* cs = wb["coef"].as_table();
  if (!cs) return;
  const std::size_t nb = m->band_edges_hz.empty() ? 0 : m->band_edges_hz.size() - 1;
  for (const auto& [k, v] : *cs) {
    const std::string e(k.str());
    const auto* a = v.as_array();
    std::vector<double> c;
    if (a)
      for (const auto& x : *a)
        if (auto d = x.value<double>()) c.push_back(*d);
    const Effect* ef = FindEffect(e);
    const bool per_band = e == effect::kCore || e == kCoefRangeLo || e == kCoefRangeHi;
    const std::size_t want =
        per_band ? nb : (ef ? nb * static_cast<std::size_t>(ef->VibrationColumns()) : 0);
    if (!a || c.size() != a->size() || c.size() != want || (!per_band && !m->Has(e)))
      diag->Add(
          path, LineOf(&v), "workbench.coef." + e,
          fmt::format("expected {} numbers (bands x columns) for a listed vibration effect", want));
    else
      m->coef[e] = std::move(c);
  }
}

}  // namespace

std::vector<std::string> ContactEffectsOf(const renderer::MaterialModel& mm) {
  std::vector<std::string> e = {std::string(effect::kCoulomb), std::string(effect::kDahl)};
  if (mm.friction.mu_b_Ns_per_m > 0) e.emplace_back(effect::kViscous);
  if (mm.contact.texture.B > 0) e.emplace_back(effect::kHcDamping);
  if (mm.contact.texture.n != 1) e.emplace_back(effect::kHcExponent);
  return e;
}

void SaveModel(const Model& m, const std::string& path, const Replay* r) {
  renderer::MaterialModel mm = RendererMaterial(m, path);
  if (m.HasVibration() && r && r->has_vibration) AddArBank(m, *r, &mm);
  std::string s =
      "# Written by the HapticLab workbench. [contact], [friction] and [vibration] are what the\n"
      "# renderer plays; [workbench] holds every effect's parameters (docs/workbench.md).\n";
  s += renderer::MaterialToToml(mm);
  s += WorkbenchToml(m);
  WriteReadBack(s, path);
}

Model LoadModel(const std::string& path) {
  const auto mm = renderer::LoadMaterial(path);  // validates the renderer's part
  const toml::table doc = ParseTomlFile(path);
  Diagnostics diag;
  Model m;
  m.name = mm.name;
  ReadEffects(mm, doc, path, &diag, &m);
  if (const toml::table* wb = doc["workbench"].as_table()) {
    ReadHeader(*wb, path, &diag, &m);
    ReadParams(*wb, path, &diag, &m);
    ReadCoefficients(*wb, path, &diag, &m);
  } else {
    BaselineOfMaterial(mm, doc, path, &diag, &m);
  }
  diag.ThrowIfAny();
  return m;
}

}  // namespace hapticlab::modeling::wb
