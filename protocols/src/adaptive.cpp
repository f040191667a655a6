#include "hapticlab/protocols/adaptive.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "adaptive_internal.hpp"
#include "hapticlab/core/fields.hpp"
#include "protocol_fields.hpp"

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
  const toml::table& table() const { return t_; }

 private:
  const toml::table& t_;
  std::string pre_, file_;
  Diagnostics* d_;
};

}  // namespace

using fields::Field;

namespace {

// Both kinds' keys and one kind's own, as one table for the reader.
std::span<const Field<AdaptiveSpec>> KindFields(bool staircase) {
  auto join = [](std::span<const Field<AdaptiveSpec>> own) {
    std::vector<Field<AdaptiveSpec>> v(AdaptiveFields().begin(), AdaptiveFields().end());
    v.insert(v.end(), own.begin(), own.end());
    return v;
  };
  static const std::vector<Field<AdaptiveSpec>> kStair = join(StaircaseFields()),
                                                kQuest = join(QuestPlusFields());
  return staircase ? kStair : kQuest;
}

// Material, method, parameter, reference, guess and fit: the keys both kinds share.
void ReadCommon(Keys& k, const Protocol& p, AdaptiveSpec* a) {
  if (!a->material.empty() && !p.FindMaterial(a->material))
    k.Error("material", "no [[material]] with id '" + a->material + "'");
  if (!a->method.empty() && !p.FindMethod(a->method))
    k.Error("method", "no [[method]] named '" + a->method + "'");
  const auto& params = AdaptiveParameters();
  if (!a->parameter.empty() &&
      std::find(params.begin(), params.end(), a->parameter) == params.end())
    k.Error("parameter", fmt::format("unknown parameter '{}' (expected one of: {})", a->parameter,
                                     fmt::join(params, ", ")));
  const bool yes_no = a->task == Task::kYesNo;
  if (!k.Has("reference")) {
    if (yes_no)
      a->reference = 0;
    else
      k.Error("reference",
              "missing; a 2AFC/3AFC phase compares each comparison with a reference value");
  }
  const double pmin = AdaptiveParameterMin(a->parameter);
  if (a->reference < pmin)
    k.Error("reference", fmt::format("expected >= {} for {}", pmin, a->parameter));
  if (k.Has("false_alarm") && !yes_no) {
    k.Error("false_alarm", "only a yes-no task has a false-alarm rate (m-AFC guess rates are 1/m)");
    a->false_alarm = 0;
  }
  const double guess = psychophysics::GuessRate(a->task, a->false_alarm);
  if (const toml::node* n = k.table().get("fit_lapse")) {
    if (n->value<std::string>() == "free")
      a->fit_lapse_free = true;
    else if (n->is_number() && *n->value<double>() >= 0 && *n->value<double>() < 0.2) {
      a->fit_lapse_free = false;
      a->fit_lapse = *n->value<double>();
    } else
      k.Error("fit_lapse", "expected \"free\" or a fixed rate 0 <= lapse < 0.2");
  }
  a->jnd_performance = 0.5 * (1 + guess);
  if (auto j = k.Number("jnd_performance")) {
    if (!(*j > guess && *j < 1))
      k.Error("jnd_performance", fmt::format("expected guess rate ({:.3g}) < p < 1", guess));
    else
      a->jnd_performance = *j;
  }
}

// Stimulus variable bounds: the parameter may not go below its minimum; a Weibull needs x > 0.
void CheckDomain(Keys& k, const AdaptiveSpec& a, const char* key, const std::vector<double>& xs) {
  const double pmin = AdaptiveParameterMin(a.parameter);
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
}

void ReadStaircase(Keys& k, AdaptiveSpec* a) {
  auto& c = a->staircase;
  if (auto v = k.Numbers("steps", false)) {
    if (std::any_of(v->begin(), v->end(), [](double s) { return !(s > 0); }))
      k.Error("steps", "steps must be > 0");
    else
      c.step_sizes = *v;
  } else if (!k.Has("steps")) {
    k.Error("steps", "missing; expected the step sizes, e.g. [0.2, 0.1, 0.05]");
  }
  if (auto v = k.Numbers("start", false))
    c.start_levels = *v;
  else if (!k.Has("start"))
    k.Error("start", "missing; expected a start level (one per interleaved track)");
  const bool log = c.step_type == psychophysics::StepType::kLog;
  if (!k.Has("min")) c.min_level = log ? 0 : AdaptiveParameterMin(a->parameter) - a->reference;
  if (!k.Has("max")) c.max_level = 1e300;
  if (log && !(c.min_level > 0))
    k.Error(k.Has("min") ? "min" : "step_type", "logarithmic steps need min > 0");
  if (!(c.min_level < c.max_level)) k.Error("max", "expected min < max");
  if (c.discard_reversals >= c.max_reversals)
    k.Error("discard_reversals",
            "expected fewer than reversals (nothing would be left to average)");
  for (double s : c.start_levels)
    if (!(s >= c.min_level && s <= c.max_level))
      k.Error("start", "start levels must lie within [min, max]");
  CheckDomain(k, *a, "min", {c.min_level});
  CheckDomain(k, *a, "start", c.start_levels);
  if (k.Has("max") && c.max_level < 1e300) CheckDomain(k, *a, "max", {c.max_level});
}

void ReadQuestPlus(Keys& k, AdaptiveSpec* a) {
  auto& q = a->quest;
  q.shape = a->fit;
  q.guess = psychophysics::GuessRate(a->task, a->false_alarm);
  if (auto v = k.Numbers("stimuli", true))
    q.stimuli = *v, CheckDomain(k, *a, "stimuli", q.stimuli);
  else if (!k.Has("stimuli"))
    k.Error("stimuli", "missing; expected the stimulus domain");
  if (auto v = k.Numbers("thresholds", true)) {
    q.thresholds = *v;
    if (a->fit == Shape::kWeibull &&
        std::any_of(v->begin(), v->end(), [](double x) { return !(x > 0); }))
      k.Error("thresholds", "a Weibull needs thresholds > 0");
  } else if (!k.Has("thresholds")) {
    k.Error("thresholds", "missing; expected the threshold grid");
  }
  if (auto v = k.Numbers("slopes", true)) {
    q.slopes = *v;
    if (std::any_of(v->begin(), v->end(), [](double x) { return !(x > 0); }))
      k.Error("slopes", "slopes must be > 0");
  } else if (!k.Has("slopes")) {
    k.Error("slopes", "missing; expected the slope grid");
  }
  q.lapses = {0, 0.01, 0.02, 0.04};
  if (auto v = k.Numbers("lapses", false)) {
    q.lapses = *v;
    if (std::any_of(v->begin(), v->end(), [&](double x) { return !(x >= 0 && x < 0.2); }))
      k.Error("lapses", "lapse rates must be in [0, 0.2)");
  }
  if (q.stimuli.size() * q.thresholds.size() * q.slopes.size() * q.lapses.size() > 20'000'000)
    k.Error("thresholds", "the grid (stimuli x thresholds x slopes x lapses) exceeds 2e7 points");
}

void ReadObserver(Keys& k, const std::string& pre, const std::string& file, Diagnostics* d,
                  AdaptiveSpec* a) {
  const toml::node* n = k.table().get("simulated_observer");
  if (!n) return;
  const toml::table* o = n->as_table();
  if (!o) {
    k.Error("simulated_observer", "expected a table { function, threshold, slope, lapse }");
    return;
  }
  psychophysics::SimulatedObserverParams so;
  so.false_alarm = a->false_alarm;
  so.shape = a->fit;
  so.slope = 1;
  fields::FieldReader r(*o, pre + ".simulated_observer", file, d);
  r.Read(ObserverFields(), &so);
  if (r.Has("threshold") && so.shape == Shape::kWeibull && !(so.threshold > 0))
    r.Error("threshold", "a Weibull needs threshold > 0");
  a->simulated_observer = so;
}

}  // namespace

void ParseAdaptivePhase(const toml::table& t, const std::string& pre, const std::string& file,
                        const Protocol& p, Diagnostics* d, Phase* ph) {
  const bool stair = ph->kind == PhaseKind::kStaircase;
  Keys k(t, pre, file, d);
  const std::size_t before = d->size();
  AdaptiveSpec a;
  fields::FieldReader(t, pre, file, d).Read(KindFields(stair), &a);
  ReadCommon(k, p, &a);
  if (stair)
    ReadStaircase(k, &a);
  else
    ReadQuestPlus(k, &a);
  ReadObserver(k, pre, file, d, &a);
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
