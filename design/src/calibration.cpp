#include "hapticlab/design/calibration.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <thread>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/stats/power.hpp"

namespace hapticlab::design {
namespace {

namespace fs = std::filesystem;

int Line(const toml::node* n) { return n ? static_cast<int>(n->source().begin.line) : 1; }

bool SameScales(const sim::ObserverParams& a, const sim::ObserverParams& b) {
  return a.scale_vibration == b.scale_vibration && a.scale_fluctuation == b.scale_fluctuation &&
         a.scale_friction == b.scale_friction && a.scale_stiffness == b.scale_stiffness &&
         a.scale_pattern == b.scale_pattern;
}

// The pool's trials with each criterion's feature distance recomputed from the recorded features
// by `observer`'s perceptual scales (Observer::Distance, the runner's own code).
FeltPool Rescaled(const FeltPool& pool, const sim::ObserverParams& observer) {
  FeltPool out = pool;
  out.observer = observer;
  const sim::Observer obs(observer, 0, pool.criteria);
  for (auto& trials : out.participants)
    for (auto& tr : trials)
      for (std::size_t c = 0; c < pool.criteria.size() && c < tr.distances.size(); ++c)
        tr.distances[c] = obs.Distance(pool.criteria[c], tr.felt[0], tr.felt[1]);
  return out;
}

// The main-phase rows as stats::AnalyseOnce wants them (participant, criterion, method, material).
stats::LongTable MainOnly(const stats::LongTable& t) {
  stats::LongTable m;
  m.key_names = {"participant", "criterion", "method", "material"};
  m.keys.assign(4, {});
  m.y_name = t.y_name;
  const std::size_t P = t.Key("participant"), C = t.Key("criterion"), Ph = t.Key("phase"),
                    Me = t.Key("method"), Ma = t.Key("material");
  for (std::size_t i = 0; i < t.rows(); ++i) {
    if (t.keys[Ph][i] != "main") continue;
    m.keys[0].push_back(t.keys[P][i]);
    m.keys[1].push_back(t.keys[C][i]);
    m.keys[2].push_back(t.keys[Me][i]);
    m.keys[3].push_back(t.keys[Ma][i]);
    m.y.push_back(t.y[i]);
  }
  return m;
}

// Each target's statistic in one simulated study (NaN where it does not exist).
std::vector<double> Statistics(const stats::LongTable& t,
                               const std::vector<const CalibrationTarget*>& targets) {
  std::vector<double> out(targets.size(), NAN);
  std::vector<stats::PowerTally> anova;
  bool analysed = false;
  const std::size_t C = t.Key("criterion"), Ph = t.Key("phase"), Me = t.Key("method"),
                    Ma = t.Key("material"), Co = t.Key("comparison");
  for (std::size_t k = 0; k < targets.size(); ++k) {
    const auto& g = *targets[k];
    if (g.statistic == "pes") {
      if (!analysed) {
        anova = stats::AnalyseOnce(MainOnly(t), 0.05);
        analysed = true;
      }
      for (const auto& e : anova)
        if (e.criterion == g.criterion && e.effect == g.effect) out[k] = e.sum_pes;
      continue;
    }
    double s = 0, s2 = 0;
    long n = 0;
    for (std::size_t i = 0; i < t.rows(); ++i) {
      if (t.keys[C][i] != g.criterion) continue;
      bool use = false;
      if (g.statistic == "method_mean")
        use = t.keys[Ph][i] == "main" && t.keys[Me][i] == g.method;
      else if (g.statistic == "sd")
        use = t.keys[Ph][i] == "main";
      else if (g.statistic == "upper_limit")
        use = t.keys[Ph][i] == "reference" && t.keys[Ma][i] == t.keys[Co][i];
      else if (g.statistic == "lower_limit")
        use = t.keys[Ph][i] == "reference" && t.keys[Ma][i] != t.keys[Co][i];
      if (!use) continue;
      s += t.y[i];
      s2 += t.y[i] * t.y[i];
      ++n;
    }
    if (n < 2) continue;
    const double mean = s / static_cast<double>(n);
    out[k] = g.statistic == "sd"
                 ? std::sqrt(std::max(0.0, (s2 - static_cast<double>(n) * mean * mean) /
                                               static_cast<double>(n - 1)))
                 : mean;
  }
  return out;
}

}  // namespace

bool IsScaleParam(const std::string& name) {
  return name == "scale_vibration" || name == "scale_fluctuation" || name == "scale_friction" ||
         name == "scale_stiffness" || name == "scale_pattern";
}

namespace {

// Typed reads of the targets file that record every problem (file, line, key) in `d`.
struct SpecReader {
  const std::string& path;
  Diagnostics& d;

  std::string Str(const toml::table& t, const std::string& pre, const char* key,
                  bool required) const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) d.Add(path, Line(&t), pre + "." + key, "missing; expected a string");
      return "";
    }
    if (auto v = n->value<std::string>()) return *v;
    d.Add(path, Line(n), pre + "." + key, "expected a string");
    return "";
  }
  double Num(const toml::table& t, const std::string& pre, const char* key, double lo, double hi,
             bool required, double def) const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required)
        d.Add(path, Line(&t), pre + "." + key,
              fmt::format("missing; expected a number in [{}, {}]", lo, hi));
      return def;
    }
    auto v = n->value<double>();
    if (!v || !(*v >= lo && *v <= hi)) {
      d.Add(path, Line(n), pre + "." + key, fmt::format("expected a number in [{}, {}]", lo, hi));
      return def;
    }
    return *v;
  }
  void Known(const toml::table& t, const std::string& pre,
             std::initializer_list<const char*> keys) const {
    for (const auto& [k, v] : t)
      if (std::find(keys.begin(), keys.end(), k.str()) == keys.end())
        d.Add(path, Line(&v), pre + "." + std::string(k.str()), "unknown key (a typo?)");
  }
};

// The tables of array `name` with their key prefixes ("param[2]").
std::vector<std::pair<const toml::table*, std::string>> Tables(const toml::table& doc,
                                                               const char* name) {
  std::vector<std::pair<const toml::table*, std::string>> out;
  if (const toml::array* a = doc[name].as_array())
    for (std::size_t i = 0; i < a->size(); ++i)
      if (const toml::table* t = (*a)[i].as_table())
        out.emplace_back(t, fmt::format("{}[{}]", name, i));
  return out;
}

void ReadFit(const SpecReader& r, const toml::table& doc, const fs::path& dir, CalibrationSpec& s) {
  const toml::table* f = doc["fit"].as_table();
  if (!f) {
    r.d.Add(r.path, 1, "fit", "missing [fit] table");
    return;
  }
  r.Known(*f, "fit", {"seed", "simulations", "pool", "sweeps", "observer", "start"});
  s.seed = static_cast<std::uint64_t>(r.Num(*f, "fit", "seed", 0, 9.0e15, false, 1));
  s.simulations = static_cast<int>(r.Num(*f, "fit", "simulations", 1, 100000, false, 16));
  s.pool = static_cast<int>(r.Num(*f, "fit", "pool", 1, 200, false, 6));
  s.sweeps = static_cast<int>(r.Num(*f, "fit", "sweeps", 0, 1000, false, 10));
  s.observer_out = (dir / r.Str(*f, "fit", "observer", true)).string();
  const std::string start = r.Str(*f, "fit", "start", false);
  s.start = start.empty() ? "" : (dir / start).string();
}

CalibrationParam ReadParam(const SpecReader& r, const toml::table& t, const std::string& pre) {
  static const char* const kFields[] = {"sensitivity", "offset_sd", "material_sd", "method_sd",
                                        "noise_sd"};
  r.Known(t, pre, {"name", "lo", "hi", "step"});
  CalibrationParam p;
  p.name = r.Str(t, pre, "name", true);
  const auto dot = p.name.find('.');
  const bool scale = IsScaleParam(p.name);
  const bool ok = p.name == "upper" || p.name == "lower" || p.name == "range_sd" ||
                  p.name == "lapse_rate" || scale ||
                  (dot != std::string::npos && dot > 0 &&
                   std::any_of(std::begin(kFields), std::end(kFields),
                               [&](const char* f) { return p.name.substr(dot + 1) == f; }));
  if (!p.name.empty() && !ok)
    r.d.Add(r.path, Line(t.get("name")), pre + ".name",
            "expected upper, lower, range_sd, lapse_rate, "
            "scale_(vibration|fluctuation|friction|stiffness|pattern) or "
            "CRITERION.(sensitivity|offset_sd|material_sd|method_sd|noise_sd)");
  // A perceptual scale divides a feature difference: the observer file accepts [0.001, 10].
  const double lim_lo = scale ? 1e-3 : -1e6, lim_hi = scale ? 10 : 1e6;
  p.lo = r.Num(t, pre, "lo", lim_lo, lim_hi, true, 0);
  p.hi = r.Num(t, pre, "hi", lim_lo, lim_hi, true, 1);
  p.step = r.Num(t, pre, "step", 1e-9, 1e6, true, 0.1);
  if (!(p.lo < p.hi)) r.d.Add(r.path, Line(&t), pre + ".hi", "expected hi > lo");
  return p;
}

CalibrationTarget ReadTarget(const SpecReader& r, const toml::table& t, const std::string& pre,
                             const std::vector<CalibrationProtocol>& protocols) {
  r.Known(t, pre,
          {"protocol", "statistic", "criterion", "effect", "method", "value", "weight", "source"});
  CalibrationTarget g;
  g.line = Line(&t);
  g.protocol = r.Str(t, pre, "protocol", true);
  if (!g.protocol.empty() &&
      std::none_of(protocols.begin(), protocols.end(),
                   [&](const CalibrationProtocol& p) { return p.id == g.protocol; }))
    r.d.Add(r.path, Line(t.get("protocol")), pre + ".protocol",
            "no [[protocol]] with id '" + g.protocol + "'");
  g.statistic = r.Str(t, pre, "statistic", true);
  g.criterion = r.Str(t, pre, "criterion", true);
  if (g.statistic == "pes") {
    g.effect = r.Str(t, pre, "effect", true);
    if (!g.effect.empty() && g.effect != "method" && g.effect != "material" &&
        g.effect != "method:material")
      r.d.Add(r.path, Line(t.get("effect")), pre + ".effect",
              "expected method, material or method:material");
  } else if (g.statistic == "method_mean") {
    g.method = r.Str(t, pre, "method", true);
  } else if (!g.statistic.empty() && g.statistic != "sd" && g.statistic != "upper_limit" &&
             g.statistic != "lower_limit") {
    r.d.Add(r.path, Line(t.get("statistic")), pre + ".statistic",
            "expected pes, method_mean, sd, upper_limit or lower_limit");
  }
  g.value = r.Num(t, pre, "value", -1e6, 1e6, true, 0);
  g.weight = r.Num(t, pre, "weight", 0, 1e9, true, 1);
  return g;
}

}  // namespace

CalibrationSpec LoadCalibration(const std::string& path) {
  const toml::table doc = ParseTomlFile(path, "calibration targets file");
  Diagnostics d;
  const SpecReader r{path, d};
  CalibrationSpec s;
  s.path = path;
  const fs::path dir = fs::path(path).parent_path();
  r.Known(doc, "", {"fit", "protocol", "param", "target"});
  ReadFit(r, doc, dir, s);
  for (const auto& [t, pre] : Tables(doc, "protocol")) {
    r.Known(*t, pre, {"id", "file", "participants"});
    CalibrationProtocol p;
    p.id = r.Str(*t, pre, "id", true);
    p.file = (dir / r.Str(*t, pre, "file", true)).string();
    p.participants = static_cast<int>(r.Num(*t, pre, "participants", 2, 1000, true, 15));
    s.protocols.push_back(p);
  }
  if (s.protocols.empty()) d.Add(path, 1, "protocol", "no [[protocol]] tables");
  for (const auto& [t, pre] : Tables(doc, "param")) s.params.push_back(ReadParam(r, *t, pre));
  for (const auto& [t, pre] : Tables(doc, "target"))
    s.targets.push_back(ReadTarget(r, *t, pre, s.protocols));
  if (s.targets.empty()) d.Add(path, 1, "target", "no [[target]] tables");
  d.ThrowIfAny();
  return s;
}

CalibrationState PrepareCalibration(const CalibrationSpec& spec,
                                    const std::function<void(const std::string&)>& log) {
  CalibrationState st;
  for (const auto& p : spec.protocols) {
    const auto proto = protocols::LoadProtocol(p.file);
    if (log)
      log(fmt::format("recording the physics of {} ({} participants through the runner)", p.id,
                      spec.pool));
    st.pools.push_back(RecordFeltPool(proto, spec.pool, 2, log, spec.pool_first));
  }
  st.start = spec.start.empty() ? st.pools.front().observer : sim::LoadObserver(spec.start);
  return st;
}

double EvaluateCalibration(const CalibrationState& st, const CalibrationSpec& spec,
                           const sim::ObserverParams& observer, std::vector<CalibrationRow>* rows,
                           int threads) {
  double loss = 0;
  if (rows) rows->clear();
  for (std::size_t pi = 0; pi < spec.protocols.size(); ++pi) {
    std::vector<const CalibrationTarget*> targets;
    for (const auto& t : spec.targets)
      if (t.protocol == spec.protocols[pi].id) targets.push_back(&t);
    if (targets.empty()) continue;
    // The recorded distances hold for the recording observer's scales; others re-measure them.
    std::optional<FeltPool> rescaled;
    if (!SameScales(st.pools[pi].observer, observer)) rescaled = Rescaled(st.pools[pi], observer);
    const FeltPool& pool = rescaled ? *rescaled : st.pools[pi];
    std::vector<std::vector<double>> per(static_cast<std::size_t>(spec.simulations));
    std::atomic<int> next{0};
    auto work = [&] {
      for (int s; (s = next.fetch_add(1)) < spec.simulations;) {
        Rng rng(DeriveSeed(DeriveSeed(spec.seed, pi), static_cast<std::uint64_t>(s)));
        per[static_cast<std::size_t>(s)] = Statistics(
            SimulateRatings(pool, observer, spec.protocols[pi].participants, rng, false), targets);
      }
    };
    std::vector<std::thread> ts;
    for (int t = 1; t < threads; ++t) ts.emplace_back(work);
    work();
    for (auto& t : ts) t.join();
    for (std::size_t k = 0; k < targets.size(); ++k) {
      double sum = 0;
      int n = 0;
      for (const auto& v : per)
        if (std::isfinite(v[k])) {
          sum += v[k];
          ++n;
        }
      const double achieved = n ? sum / n : NAN;
      const auto& g = *targets[k];
      // A statistic the design cannot produce counts as a large miss.
      loss +=
          std::isfinite(achieved) ? g.weight * (achieved - g.value) * (achieved - g.value) : 1e6;
      if (rows) {
        std::string label = g.statistic + " " + g.criterion;
        if (!g.effect.empty()) label += " " + g.effect;
        if (!g.method.empty()) label += " " + g.method;
        rows->push_back({g.protocol, label, g.value, g.weight, achieved});
      }
    }
  }
  return loss;
}

}  // namespace hapticlab::design
