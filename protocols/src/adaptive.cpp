#include "hapticlab/protocols/adaptive.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "adaptive_internal.hpp"

namespace hapticlab::protocols {

const std::vector<std::string>& AdaptiveParameters() {
  static const std::vector<std::string> kParameters{"vibration.gain", "geometry.amplitude_scale",
                                                    "contact.K", "friction.mu_k",
                                                    "friction.mu_b_Ns_per_m"};
  return kParameters;
}

double AdaptiveParameterMin(const std::string& parameter) {
  return parameter == "contact.K" ? 1e-9 : 0.0;
}

namespace internal {
namespace {

using psychophysics::Shape;
using psychophysics::Task;

class Keys {
 public:
  Keys(const toml::table& t, std::string prefix, std::string file, Diagnostics* d)
      : t_(t), pre_(std::move(prefix)), file_(std::move(file)), d_(d) {}
  static int Line(const toml::node* n) { return n ? static_cast<int>(n->source().begin.line) : 0; }
  void Error(const char* key, const std::string& msg) {
    const toml::node* n = t_.get(key);
    d_->Add(file_, Line(n ? n : &t_), pre_ + "." + key, msg);
  }
  bool Has(const char* key) const { return t_.contains(key); }
  std::string String(const char* key, bool required, const std::string& def, const char* expected) {
    const toml::node* n = t_.get(key);
    if (!n) {
      if (required) Error(key, std::string("missing; expected ") + expected);
      return def;
    }
    if (auto v = n->value<std::string>()) return *v;
    Error(key, std::string("expected ") + expected);
    return def;
  }
  std::optional<double> Number(const char* key) {
    const toml::node* n = t_.get(key);
    if (!n) return std::nullopt;
    if (n->is_number()) {
      const double v = *n->value<double>();
      if (std::isfinite(v)) return v;
    }
    Error(key, "expected a finite number");
    return std::nullopt;
  }
  std::optional<int> Int(const char* key, int lo, int hi) {
    const toml::node* n = t_.get(key);
    if (!n) return std::nullopt;
    auto v = n->value<std::int64_t>();
    if (!n->is_integer() || *v < lo || *v > hi) {
      Error(key, fmt::format("expected an integer {}..{}", lo, hi));
      return std::nullopt;
    }
    return static_cast<int>(*v);
  }
  // A number or an array of numbers; or a { from, to, count, spacing } range when allowed.
  std::optional<std::vector<double>> Numbers(const char* key, bool allow_range) {
    const toml::node* n = t_.get(key);
    if (!n) return std::nullopt;
    std::vector<double> out;
    if (n->is_number()) {
      out.push_back(*n->value<double>());
    } else if (const toml::array* a = n->as_array()) {
      for (const auto& x : *a) {
        if (!x.is_number()) {
          Error(key, "expected numbers");
          return std::nullopt;
        }
        out.push_back(*x.value<double>());
      }
    } else if (const toml::table* r = n->as_table(); r && allow_range) {
      const auto from = (*r)["from"].value<double>(), to = (*r)["to"].value<double>();
      const auto count = (*r)["count"].value<std::int64_t>();
      const std::string spacing = (*r)["spacing"].value_or(std::string("linear"));
      bool known = true;
      for (const auto& [k, v] : *r)
        known = known && (k.str() == "from" || k.str() == "to" || k.str() == "count" ||
                          k.str() == "spacing");
      if (!from || !to || !count || *count < 2 || *count > 1000 || !(*from < *to) || !known ||
          (spacing != "linear" && spacing != "log") || (spacing == "log" && !(*from > 0))) {
        Error(key,
              "expected { from = a, to = b, count = 2..1000, spacing = \"linear\" or \"log\" } "
              "with a < b "
              "(a > 0 for log)");
        return std::nullopt;
      }
      for (std::int64_t i = 0; i < *count; ++i) {
        const double f = static_cast<double>(i) / static_cast<double>(*count - 1);
        out.push_back(spacing == "log" ? *from * std::pow(*to / *from, f)
                                       : *from + (*to - *from) * f);
      }
    } else {
      Error(key, allow_range
                     ? "expected a number, an array of numbers or { from, to, count, spacing }"
                     : "expected a number or an array of numbers");
      return std::nullopt;
    }
    if (out.empty() ||
        std::any_of(out.begin(), out.end(), [](double v) { return !std::isfinite(v); })) {
      Error(key, "expected at least one finite number");
      return std::nullopt;
    }
    return out;
  }
  void Known(std::initializer_list<const char*> keys) {
    for (const auto& [k, v] : t_)
      if (std::none_of(keys.begin(), keys.end(),
                       [&key = k](const char* x) { return key.str() == x; }))
        d_->Add(file_, Line(&v), pre_ + "." + std::string(k.str()), "unknown key (a typo?)");
  }
  const toml::table& table() const { return t_; }

 private:
  const toml::table& t_;
  std::string pre_, file_;
  Diagnostics* d_;
};

}  // namespace

void ParseAdaptivePhase(const toml::table& t, const std::string& pre, const std::string& file,
                        const Protocol& p, Diagnostics* d, Phase* ph) {
  const bool stair = ph->kind == PhaseKind::kStaircase;
  Keys k(t, pre, file, d);
  const std::size_t before = d->size();
  if (stair)
    k.Known({"kind",
             "material",
             "method",
             "parameter",
             "task",
             "reference",
             "false_alarm",
             "fit",
             "fit_lapse",
             "jnd_performance",
             "simulated_observer",
             "up",
             "down",
             "step_type",
             "steps",
             "start",
             "min",
             "max",
             "reversals",
             "max_trials",
             "discard_reversals"});
  else
    k.Known({"kind", "material", "method", "parameter", "task", "reference", "false_alarm", "fit",
             "fit_lapse", "jnd_performance", "simulated_observer", "stimuli", "thresholds",
             "slopes", "lapses", "trials"});
  AdaptiveSpec a;
  a.material = k.String("material", true, "", "a material id");
  if (!a.material.empty() && !p.FindMaterial(a.material))
    k.Error("material", "no [[material]] with id '" + a.material + "'");
  a.method = k.String("method", true, "", "a method name");
  if (!a.method.empty() && !p.FindMethod(a.method))
    k.Error("method", "no [[method]] named '" + a.method + "'");
  a.parameter = k.String("parameter", true, "", "a parameter name");
  const auto& params = AdaptiveParameters();
  if (!a.parameter.empty() && std::find(params.begin(), params.end(), a.parameter) == params.end())
    k.Error("parameter", fmt::format("unknown parameter '{}' (expected one of: {})", a.parameter,
                                     fmt::join(params, ", ")));
  const std::string task = k.String("task", false, "2afc", "2afc, 3afc or yes-no");
  if (auto tk = psychophysics::ParseTask(task))
    a.task = *tk;
  else
    k.Error("task", "expected 2afc, 3afc or yes-no, got '" + task + "'");
  const bool yes_no = a.task == Task::kYesNo;
  if (auto r = k.Number("reference"))
    a.reference = *r;
  else if (!k.Has("reference")) {
    if (yes_no)
      a.reference = 0;
    else
      k.Error("reference",
              "missing; a 2AFC/3AFC phase compares each comparison with a reference value");
  }
  const double pmin = AdaptiveParameterMin(a.parameter);
  if (a.reference < pmin)
    k.Error("reference", fmt::format("expected >= {} for {}", pmin, a.parameter));
  if (auto fa = k.Number("false_alarm")) {
    if (!yes_no)
      k.Error("false_alarm",
              "only a yes-no task has a false-alarm rate (m-AFC guess rates are 1/m)");
    else if (!(*fa >= 0 && *fa < 0.5))
      k.Error("false_alarm", "expected 0 <= rate < 0.5");
    else
      a.false_alarm = *fa;
  }
  const double guess = psychophysics::GuessRate(a.task, a.false_alarm);
  const std::string fit = k.String("fit", false, "weibull", "logistic, weibull or normal");
  if (auto s = psychophysics::ParseShape(fit))
    a.fit = *s;
  else
    k.Error("fit", "expected logistic, weibull or normal, got '" + fit + "'");
  if (const toml::node* n = t.get("fit_lapse")) {
    if (n->value<std::string>() == "free")
      a.fit_lapse_free = true;
    else if (n->is_number() && *n->value<double>() >= 0 && *n->value<double>() < 0.2) {
      a.fit_lapse_free = false;
      a.fit_lapse = *n->value<double>();
    } else
      k.Error("fit_lapse", "expected \"free\" or a fixed rate 0 <= lapse < 0.2");
  }
  a.jnd_performance = 0.5 * (1 + guess);
  if (auto j = k.Number("jnd_performance")) {
    if (!(*j > guess && *j < 1))
      k.Error("jnd_performance", fmt::format("expected guess rate ({:.3g}) < p < 1", guess));
    else
      a.jnd_performance = *j;
  }
  // Stimulus variable bounds: the parameter may not go below its minimum; a Weibull needs x > 0.
  auto check_domain = [&](const char* key, const std::vector<double>& xs) {
    for (double x : xs) {
      if (a.reference + x < pmin) {
        k.Error(key, fmt::format("{} + {} = {} is below the smallest {} ({})", a.reference, x,
                                 a.reference + x, a.parameter, pmin));
        return;
      }
      if (a.fit == Shape::kWeibull && !(x > 0)) {
        k.Error(key,
                "fit = \"weibull\" needs stimulus differences > 0 (or use fit = \"logistic\" / "
                "\"normal\")");
        return;
      }
    }
  };

  if (stair) {
    auto& c = a.staircase;
    if (auto v = k.Int("up", 1, 5)) c.up = *v;
    if (auto v = k.Int("down", 1, 5)) c.down = *v;
    const std::string st = k.String("step_type", false, "linear", "linear or log");
    if (st == "linear")
      c.step_type = psychophysics::StepType::kLinear;
    else if (st == "log")
      c.step_type = psychophysics::StepType::kLog;
    else
      k.Error("step_type", "expected linear or log, got '" + st + "'");
    if (auto v = k.Numbers("steps", false)) {
      if (std::any_of(v->begin(), v->end(), [](double s) { return !(s > 0); }))
        k.Error("steps", "steps must be > 0");
      else
        c.step_sizes = *v;
    } else if (!k.Has("steps"))
      k.Error("steps", "missing; expected the step sizes, e.g. [0.2, 0.1, 0.05]");
    if (auto v = k.Numbers("start", false))
      c.start_levels = *v;
    else if (!k.Has("start"))
      k.Error("start", "missing; expected a start level (one per interleaved track)");
    c.min_level = k.Number("min").value_or(
        c.step_type == psychophysics::StepType::kLog ? 0 : pmin - a.reference);
    c.max_level = k.Number("max").value_or(1e300);
    if (c.step_type == psychophysics::StepType::kLog && !(c.min_level > 0))
      k.Error(k.Has("min") ? "min" : "step_type", "logarithmic steps need min > 0");
    if (!(c.min_level < c.max_level)) k.Error("max", "expected min < max");
    if (auto v = k.Int("reversals", 1, 1000)) c.max_reversals = *v;
    if (auto v = k.Int("max_trials", 1, 10000)) c.max_trials = *v;
    if (auto v = k.Int("discard_reversals", 0, 1000)) c.discard_reversals = *v;
    if (c.discard_reversals >= c.max_reversals)
      k.Error("discard_reversals",
              "expected fewer than reversals (nothing would be left to average)");
    for (double s : c.start_levels)
      if (!(s >= c.min_level && s <= c.max_level))
        k.Error("start", "start levels must lie within [min, max]");
    check_domain("min", {c.min_level});
    check_domain("start", c.start_levels);
    if (k.Has("max") && c.max_level < 1e300) check_domain("max", {c.max_level});
  } else {
    auto& q = a.quest;
    q.shape = a.fit;
    q.guess = guess;
    if (auto v = k.Numbers("stimuli", true))
      q.stimuli = *v, check_domain("stimuli", q.stimuli);
    else if (!k.Has("stimuli"))
      k.Error("stimuli", "missing; expected the stimulus domain");
    if (auto v = k.Numbers("thresholds", true)) {
      q.thresholds = *v;
      if (a.fit == Shape::kWeibull &&
          std::any_of(v->begin(), v->end(), [](double x) { return !(x > 0); }))
        k.Error("thresholds", "a Weibull needs thresholds > 0");
    } else if (!k.Has("thresholds"))
      k.Error("thresholds", "missing; expected the threshold grid");
    if (auto v = k.Numbers("slopes", true)) {
      q.slopes = *v;
      if (std::any_of(v->begin(), v->end(), [](double x) { return !(x > 0); }))
        k.Error("slopes", "slopes must be > 0");
    } else if (!k.Has("slopes"))
      k.Error("slopes", "missing; expected the slope grid");
    q.lapses = {0, 0.01, 0.02, 0.04};
    if (auto v = k.Numbers("lapses", false)) {
      q.lapses = *v;
      if (std::any_of(v->begin(), v->end(), [&](double x) { return !(x >= 0 && x < 0.2); }))
        k.Error("lapses", "lapse rates must be in [0, 0.2)");
    }
    if (q.stimuli.size() * q.thresholds.size() * q.slopes.size() * q.lapses.size() > 20'000'000)
      k.Error("thresholds", "the grid (stimuli x thresholds x slopes x lapses) exceeds 2e7 points");
    if (auto v = k.Int("trials", 1, 10000)) a.quest_trials = *v;
  }

  if (const toml::node* n = t.get("simulated_observer")) {
    const toml::table* o = n->as_table();
    if (!o) {
      k.Error("simulated_observer", "expected a table { function, threshold, slope, lapse }");
    } else {
      Keys ok(*o, pre + ".simulated_observer", file, d);
      ok.Known({"function", "threshold", "slope", "lapse"});
      psychophysics::SimulatedObserverParams so;
      so.false_alarm = a.false_alarm;
      const std::string f = ok.String("function", false, psychophysics::ToString(a.fit),
                                      "logistic, weibull or normal");
      if (auto s = psychophysics::ParseShape(f))
        so.shape = *s;
      else
        ok.Error("function", "expected logistic, weibull or normal, got '" + f + "'");
      const auto thr = ok.Number("threshold"), slope = ok.Number("slope");
      if (!thr)
        ok.Error("threshold",
                 "missing; expected the observer's true threshold (stimulus difference)");
      if (!slope || !(*slope > 0)) ok.Error("slope", "expected the observer's true slope > 0");
      if (thr && so.shape == Shape::kWeibull && !(*thr > 0))
        ok.Error("threshold", "a Weibull needs threshold > 0");
      so.threshold = thr.value_or(1);
      so.slope = slope.value_or(1);
      so.lapse = ok.Number("lapse").value_or(0);
      if (!(so.lapse >= 0 && so.lapse < 0.2)) ok.Error("lapse", "expected 0 <= lapse < 0.2");
      a.simulated_observer = so;
    }
  }
  // Cross-checks the pure components make (only when the keys themselves were fine).
  if (d->size() == before) {
    std::string why;
    if (stair && !a.staircase.IsValid(&why)) k.Error("steps", why);
    if (!stair && !a.quest.IsValid(&why)) k.Error("stimuli", why);
  }
  ph->adaptive = std::move(a);
}

}  // namespace internal
}  // namespace hapticlab::protocols
