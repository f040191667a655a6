// Workbench models: the core effect, effect lookup, resolving a model into parameter vectors,
// adding effects (DESIGN.md §4).

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "workbench_internal.hpp"

namespace hapticlab::modeling::wb {

namespace internal {
namespace {

// The core every model has: the contact stiffness K (force at 1 mm penetration).
class Core final : public Effect {
 public:
  std::string_view name() const override { return effect::kCore; }
  Channel channel() const override { return Channel::kNormal; }
  std::string_view description() const override { return "contact stiffness"; }
  std::vector<ParamSpec> Params(const Replay& r) const override {
    // Initial K: median of f_n / (d / 1 mm) over samples in contact.
    std::vector<double> k;
    for (const auto& s : r.samples())
      if (s.contact && s.d_m > 1e-5) k.push_back(s.fn_N / (s.d_m / kMm));
    double init = 1;
    if (!k.empty()) {
      std::nth_element(k.begin(), k.begin() + k.size() / 2, k.end());
      init = std::max(k[k.size() / 2], 1e-3);
    }
    return {{.name = std::string(key::kK1mm_N.name),
             .unit = "N",
             .init = init,
             .lo = 1e-6,
             .hi = 1e6,
             .scale = init,
             .fitted = true,
             .doc = "normal force at 1 mm penetration"}};
  }
  void Normal(const double* p, const Replay::Sample&, NormalTerms& t) const override { t.K = p[0]; }
  EvidenceNote Evidence(const Replay&, const Residuals&) const override { return {}; }
};
const Core kCore;

const Effect* Lookup(std::string_view name) {
  return name == effect::kCore ? &kCore : FindEffect(name);
}

}  // namespace

const Effect& CoreEffect() { return kCore; }

std::vector<Resolved> Resolve(const Model& m, const Replay& r, Channel c) {
  std::vector<Resolved> out;
  std::vector<std::string> names;
  if (c == Channel::kNormal) names.emplace_back(effect::kCore);
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

}  // namespace internal

using internal::CoreEffect;

const char* ChannelName(Channel c) {
  const std::string_view name = NameOf(kChannelNames, c);  // the table's literals end in NUL
  return name.empty() ? "?" : name.data();
}

const Effect* FindEffect(std::string_view name) {
  for (const auto& e : Catalogue())
    if (e->name() == name) return e.get();
  return nullptr;
}

std::vector<std::string> BaselineEffects() {
  using namespace effect;
  return {std::string(kCoulomb),       std::string(kViscous),    std::string(kDahl),
          std::string(kHcDamping),     std::string(kHcExponent), std::string(kVibrationSpeed),
          std::string(kVibrationForce)};
}

bool Model::Has(std::string_view e) const {
  return std::find(effects.begin(), effects.end(), e) != effects.end();
}

double Model::Get(ParamKey k, double fallback) const {
  const auto it = params.find(std::string(k.effect));
  if (it == params.end()) return fallback;
  const auto jt = it->second.find(std::string(k.name));
  return jt == it->second.end() ? fallback : jt->second;
}

double Model::At(ParamKey k) const {
  const double v = Get(k, std::numeric_limits<double>::quiet_NaN());
  HL_REQUIRE(!std::isnan(v), fmt::format("the model has no parameter {}.{}", k.effect, k.name));
  return v;
}

void Model::Set(ParamKey k, double value) {
  params[std::string(k.effect)][std::string(k.name)] = value;
}

ContactParameters ContactParameters::From(const Model& m, double no_dahl_kappa_N_per_m) {
  constexpr double kDahlInit_N_per_m = 2000;  // effects/dahl.cpp's initial value
  ContactParameters c;
  c.K1mm_N = m.Get(key::kK1mm_N, 1);
  c.n = m.Has(effect::kHcExponent) ? m.Get(key::kN, 1) : 1;
  c.B1mm_Ns_per_m = m.Has(effect::kHcDamping) ? m.Get(key::kB1mm_Ns_per_m, 0) : 0;
  c.mu_k = m.Has(effect::kCoulomb) ? m.Get(key::kMuK, 0) : 0;
  c.mu_b_Ns_per_m = m.Has(effect::kViscous) ? m.Get(key::kMuB_Ns_per_m, 0) : 0;
  c.kappa_N_per_m =
      m.Has(effect::kDahl) ? m.Get(key::kKappa_N_per_m, kDahlInit_N_per_m) : no_dahl_kappa_N_per_m;
  return c;
}

void ContactParameters::ToModel(Model* m) const {
  m->Set(key::kK1mm_N, K1mm_N);
  m->Set(key::kN, n);
  m->Set(key::kB1mm_Ns_per_m, B1mm_Ns_per_m);
  m->Set(key::kMuK, mu_k);
  m->Set(key::kMuB_Ns_per_m, mu_b_Ns_per_m);
  m->Set(key::kKappa_N_per_m, kappa_N_per_m);
}

double ContactParameters::K_N_per_m_pow_n() const { return K1mm_N / std::pow(internal::kMm, n); }
double ContactParameters::B_Ns_per_m_pow_n_plus_1() const {
  return B1mm_Ns_per_m / std::pow(internal::kMm, n);
}

std::string CatalogueNames() {
  std::string list;
  for (const auto& c : Catalogue()) list += (list.empty() ? "" : ", ") + std::string(c->name());
  return list;
}

void RequireKnownEffects(const std::vector<std::string>& names, const std::string& source,
                         const std::string& field) {
  Diagnostics d;
  for (const auto& n : names)
    if (!FindEffect(n))
      d.Add(source, 0, field,
            fmt::format("unknown effect '{}'; the catalogue has: {}", n, CatalogueNames()));
  d.ThrowIfAny();
}

// ---------------------------------------------------------------------------------------------
void AddEffects(Model* m, const std::vector<std::string>& names, const Replay& r) {
  std::vector<std::string> todo;
  std::function<void(const std::string&)> add = [&](const std::string& n) {
    const Effect* e = FindEffect(n);
    HL_REQUIRE(
        e != nullptr,
        fmt::format("AddEffects: unknown effect '{}' (check names with RequireKnownEffects)", n));
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
  const std::string core(effect::kCore);
  if (!m->params.count(core))
    for (const auto& s : CoreEffect().Params(r)) m->params[core][s.name] = s.init;
}

}  // namespace hapticlab::modeling::wb
