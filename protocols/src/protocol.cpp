#include "hapticlab/protocols/protocol.hpp"

#include <fmt/format.h>
#include <re2/re2.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "adaptive_internal.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/participant_code.hpp"
#include "hapticlab/core/toml_util.hpp"

namespace hapticlab::protocols {
namespace {

// Typed reads that record every problem (file, line, key) instead of stopping at the first.
class Reader {
 public:
  Reader(std::string file, Diagnostics* d) : file_(std::move(file)), d_(d) {}
  static int Line(const toml::node* n) { return n ? static_cast<int>(n->source().begin.line) : 0; }
  void Error(const toml::node* n, const std::string& key, const std::string& msg) {
    d_->Add(file_, Line(n), key, msg);
  }

  template <class T>
  std::optional<T> Get(const toml::table& t, const std::string& prefix, const char* key,
                       bool required, const char* expected) {
    const toml::node* n = t.get(key);
    const std::string full = prefix.empty() ? key : prefix + "." + key;
    if (!n) {
      if (required) d_->Add(file_, Line(&t), full, std::string("missing; expected ") + expected);
      return std::nullopt;
    }
    if (auto v = n->value<T>()) return v;
    Error(n, full, std::string("expected ") + expected);
    return std::nullopt;
  }
  std::vector<std::string> Strings(const toml::table& t, const std::string& prefix, const char* key,
                                   bool required) {
    std::vector<std::string> out;
    const toml::node* n = t.get(key);
    const std::string full = prefix.empty() ? key : prefix + "." + key;
    if (!n) {
      if (required) d_->Add(file_, Line(&t), full, "missing; expected an array of strings");
      return out;
    }
    const toml::array* a = n->as_array();
    if (!a) {
      Error(n, full, "expected an array of strings");
      return out;
    }
    for (const auto& x : *a) {
      if (auto s = x.value<std::string>())
        out.push_back(*s);
      else
        Error(&x, full, "expected strings");
    }
    return out;
  }
  void Known(const toml::table& t, const std::string& prefix,
             std::initializer_list<const char*> keys) {
    for (const auto& [k, v] : t) {
      if (std::none_of(keys.begin(), keys.end(),
                       [&key = k](const char* x) { return key.str() == x; }))
        Error(&v, prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str()),
              "unknown key (a typo?)");
    }
  }
  Diagnostics& diag() { return *d_; }
  const std::string& file() const { return file_; }

 private:
  std::string file_;
  Diagnostics* d_;
};

// The protocol's material ids, comma-separated, for messages.
std::string MaterialIds(const Protocol& p) {
  std::string s;
  std::size_t shown = 0;
  for (const auto& m : p.materials) {
    if (++shown > 20) return s + fmt::format(", ... ({} in all)", p.materials.size());
    s += (s.empty() ? "" : ", ") + m.id;
  }
  return s.empty() ? std::string("none") : s;
}

// [consent]: both keys, plain one-line text; the document is named, not located (an absolute
// path would carry a user or host name into the study record).
void ReadConsent(const toml::table& t, Reader& r, Protocol* p) {
  r.Known(t, "consent", {"document", "version"});
  p->consent_line = Reader::Line(&t);
  const auto text = [&](const char* key, std::size_t max, const char* what) {
    const std::string full = std::string("consent.") + key;
    const auto v = r.Get<std::string>(t, "consent", key, true, what);
    if (!v) return std::string();
    const bool plain = !v->empty() && v->size() <= max &&
                       std::none_of(v->begin(), v->end(), [](unsigned char c) { return c < 0x20; });
    if (!plain)
      r.Error(t.get(key), full, fmt::format("expected {} (1..{} characters, one line)", what, max));
    else if ((*v)[0] == '/' || (*v)[0] == '~' || (v->size() > 1 && (*v)[1] == ':'))
      r.Error(t.get(key), full,
              "expected the document's name or title, not an absolute path (it would put a "
              "user or host name into the study record)");
    else
      return *v;
    return std::string();
  };
  p->consent_document =
      text("document", 256, "the consent document's name or title, e.g. \"consent-form.pdf\"");
  p->consent_version = text("version", 64, "its version, e.g. \"2026-03\"");
}

// How many entries of an array of tables are read: all, or (with an error) the first `max`.
std::size_t Bounded(Reader& r, const toml::array& a, const std::string& key, std::size_t max) {
  if (a.size() <= max) return a.size();
  r.Error(&a, key, fmt::format("{} entries; at most {} are allowed", a.size(), max));
  return max;
}

const std::set<std::string> kAlgorithms{"wall", "norm", "fric1", "fric2", "none"};

}  // namespace

const char* ToString(PhaseKind k) {
  switch (k) {
    case PhaseKind::kTraining:
      return "training";
    case PhaseKind::kReference:
      return "reference";
    case PhaseKind::kMain:
      return "main";
    case PhaseKind::kStaircase:
      return "staircase";
    case PhaseKind::kQuestPlus:
      return "quest-plus";
  }
  return "?";
}

const Material* Protocol::FindMaterial(const std::string& id) const {
  for (const auto& m : materials)
    if (m.id == id) return &m;
  return nullptr;
}
const Method* Protocol::FindMethod(const std::string& n) const {
  for (const auto& m : methods)
    if (m.name == n) return &m;
  return nullptr;
}

namespace {

// The pattern compiled by RE2, whose matching time is linear in the code's length whatever the
// pattern (no backtracking: `^(A|A)*B$` costs what `^A*B$` costs). std::regex backtracked.
RE2::Options CodePatternOptions() {
  RE2::Options o;
  o.set_log_errors(false);
  o.set_max_mem(std::int64_t{1} << 20);  // a 128-character pattern needs far less
  return o;
}

}  // namespace

bool ValidCodePattern(const std::string& pattern, std::string* why) {
  if (pattern.empty() || pattern.size() > kMaxCodePatternBytes) {
    if (why)
      *why = fmt::format("expected a regular expression of 1..{} characters", kMaxCodePatternBytes);
    return false;
  }
  const RE2 re(pattern, CodePatternOptions());
  if (!re.ok()) {
    if (why)
      *why = "not a valid regular expression (RE2 syntax: no back-references or look-arounds): " +
             re.error();
    return false;
  }
  return true;
}

void CheckParticipantCode(const Protocol& p, const std::string& code) {
  const std::string rule =
      "a pseudonymous code matching " + p.participant_code +
      " (e.g. P07; 'hapticlab participant new' hands out the next free one), never a name, "
      "birth date or phone number";
  // The code must be short and plain before the pattern is even tried.
  bool plain = !code.empty() && code.size() <= 32;
  for (unsigned char c : code) plain = plain && (std::isalnum(c) || c == '-' || c == '_');
  if (!plain || !RE2::FullMatch(code, RE2(p.participant_code, CodePatternOptions())))
    throw InputError(p.file, 0, "participant", "'" + code + "' is not " + rule);
  // The database's own rule, whatever the pattern admits (Anna_Kowalski_19850312).
  if (const std::string why = PseudonymousCodeProblem(code); !why.empty())
    throw InputError(p.file, 0, "participant", "'" + code + "' is not " + rule + " (" + why + ")");
}

Protocol ParseProtocol(const std::string& text, const std::string& file) {
  const toml::table doc = ParseTomlText(text, file);
  Diagnostics diag;
  Reader r(file, &diag);
  Protocol p;
  p.file = file;
  p.text = text;
  r.Known(doc, "",
          {"study", "material", "method", "phase", "randomization", "breaks", "masking_noise",
           "consent", "analysis"});

  // [study]
  if (const toml::table* s = doc["study"].as_table()) {
    r.Known(*s, "study",
            {"name", "description", "seed", "criteria", "scale", "stimulus_duration_s", "profiles",
             "observer", "participant_code", "title"});
    p.name = r.Get<std::string>(*s, "study", "name", true, "a string").value_or("");
    p.description = r.Get<std::string>(*s, "study", "description", false, "a string").value_or("");
    p.title = r.Get<std::string>(*s, "study", "title", false, "a string").value_or(p.name);
    if (auto seed = r.Get<std::int64_t>(*s, "study", "seed", true, "a non-negative integer")) {
      if (*seed < 0) r.Error(s->get("seed"), "study.seed", "expected a non-negative integer");
      p.seed = static_cast<std::uint64_t>(*seed);
    }
    p.criteria = r.Strings(*s, "study", "criteria", true);
    if (p.criteria.empty() && s->contains("criteria"))
      r.Error(s->get("criteria"), "study.criteria", "needs at least one criterion");
    if (const toml::node* sc = s->get("scale")) {
      const toml::array* a = sc->as_array();
      if (!a || a->size() != 2 || !(*a)[0].value<double>() || !(*a)[1].value<double>() ||
          !(*(*a)[0].value<double>() < *(*a)[1].value<double>()) ||
          !std::isfinite(*(*a)[0].value<double>()) || !std::isfinite(*(*a)[1].value<double>()))
        r.Error(sc, "study.scale", "expected [min, max] with finite min < max");
      else {
        p.scale_min = *(*a)[0].value<double>();
        p.scale_max = *(*a)[1].value<double>();
      }
    }
    p.stimulus_duration_s =
        r.Get<double>(*s, "study", "stimulus_duration_s", false, "a number").value_or(2.0);
    if (!(p.stimulus_duration_s > 0 && p.stimulus_duration_s <= 600))
      r.Error(s->get("stimulus_duration_s"), "study.stimulus_duration_s",
              "expected 0 < seconds <= 600");
    p.profiles = r.Get<std::string>(*s, "study", "profiles", false, "a file name").value_or("");
    p.observer = r.Get<std::string>(*s, "study", "observer", false, "a file name").value_or("");
    if (auto pat =
            r.Get<std::string>(*s, "study", "participant_code", false, "a regular expression")) {
      std::string why;
      if (!ValidCodePattern(*pat, &why))
        r.Error(s->get("participant_code"), "study.participant_code", why);
      else
        p.participant_code = *pat;
    }
  } else {
    diag.Add(file, 1, "study", "missing [study] table");
  }

  // [[material]]
  std::set<std::string> ids;
  if (const toml::array* ms = doc["material"].as_array()) {
    for (std::size_t i = 0, n = Bounded(r, *ms, "material", kMaxMaterials); i < n; ++i) {
      const std::string pre = fmt::format("material[{}]", i);
      const toml::table* t = (*ms)[i].as_table();
      if (!t) {
        r.Error(&(*ms)[i], pre, "expected a table");
        continue;
      }
      r.Known(*t, pre, {"id", "sample", "model", "profile", "group"});
      Material m;
      m.line = Reader::Line(t);
      m.id = r.Get<std::string>(*t, pre, "id", true, "a string").value_or("");
      m.sample = r.Get<std::string>(*t, pre, "sample", false, "a string").value_or(m.id);
      m.model = r.Get<std::string>(*t, pre, "model", false, "a file or \"placeholder\"")
                    .value_or("placeholder");
      m.profile = r.Get<std::string>(*t, pre, "profile", false, "a string").value_or(m.id);
      m.group = r.Get<std::string>(*t, pre, "group", false, "a string").value_or("");
      if (!m.id.empty() && !ids.insert(m.id).second)
        r.Error(t->get("id"), pre + ".id", "duplicate material id '" + m.id + "'");
      p.materials.push_back(m);
    }
  }
  if (p.materials.empty()) diag.Add(file, 0, "material", "at least one [[material]] is needed");

  // [[method]]
  std::set<std::string> names;
  if (const toml::array* ms = doc["method"].as_array()) {
    for (std::size_t i = 0, n = Bounded(r, *ms, "method", kMaxMethods); i < n; ++i) {
      const std::string pre = fmt::format("method[{}]", i);
      const toml::table* t = (*ms)[i].as_table();
      if (!t) {
        r.Error(&(*ms)[i], pre, "expected a table");
        continue;
      }
      r.Known(*t, pre, {"name", "algorithm", "vibration", "hybrid_filter"});
      Method m;
      m.line = Reader::Line(t);
      m.name = r.Get<std::string>(*t, pre, "name", true, "a string").value_or("");
      m.algorithm =
          r.Get<std::string>(*t, pre, "algorithm", true, "wall, norm, fric1, fric2 or none")
              .value_or("");
      if (!m.algorithm.empty() && !kAlgorithms.count(m.algorithm))
        r.Error(t->get("algorithm"), pre + ".algorithm",
                "expected wall, norm, fric1, fric2 or none, got '" + m.algorithm + "'");
      m.vibration = r.Get<bool>(*t, pre, "vibration", false, "true or false").value_or(true);
      m.hybrid_filter =
          r.Get<bool>(*t, pre, "hybrid_filter", false, "true or false").value_or(true);
      if (!m.name.empty() && !names.insert(m.name).second)
        r.Error(t->get("name"), pre + ".name", "duplicate method '" + m.name + "'");
      p.methods.push_back(m);
    }
  }

  // [[phase]]
  bool has_main = false, has_adaptive = false;
  if (const toml::array* ps = doc["phase"].as_array()) {
    for (std::size_t i = 0, n_phases = Bounded(r, *ps, "phase", kMaxPhases); i < n_phases; ++i) {
      const std::string pre = fmt::format("phase[{}]", i);
      const toml::table* t = (*ps)[i].as_table();
      if (!t) {
        r.Error(&(*ps)[i], pre, "expected a table");
        continue;
      }
      Phase ph;
      ph.line = Reader::Line(t);
      // Adaptive phases (staircase, quest-plus) have keys of their own: adaptive.cpp.
      if (const auto k = t->get("kind") ? t->get("kind")->value<std::string>() : std::nullopt;
          k == "staircase" || k == "quest-plus") {
        ph.kind = *k == "staircase" ? PhaseKind::kStaircase : PhaseKind::kQuestPlus;
        internal::ParseAdaptivePhase(*t, pre, file, p, &diag, &ph);
        has_adaptive = true;
        p.phases.push_back(ph);
        continue;
      }
      r.Known(*t, pre,
              {"kind", "repetitions", "duration_s", "same_pairs", "different_pairs", "method"});
      const std::string kind =
          r.Get<std::string>(*t, pre, "kind", true,
                             "training, reference, main, staircase or quest-plus")
              .value_or("main");
      if (kind == "training")
        ph.kind = PhaseKind::kTraining;
      else if (kind == "reference")
        ph.kind = PhaseKind::kReference;
      else if (kind == "main")
        ph.kind = PhaseKind::kMain;
      else
        r.Error(t->get("kind"), pre + ".kind",
                "expected training, reference, main, staircase or quest-plus, got '" + kind + "'");
      has_main = has_main || ph.kind == PhaseKind::kMain;
      if (auto rep = r.Get<std::int64_t>(*t, pre, "repetitions", false, "an integer 1..100")) {
        if (*rep < 1 || *rep > 100)
          r.Error(t->get("repetitions"), pre + ".repetitions", "expected an integer 1..100");
        else
          ph.repetitions = static_cast<int>(*rep);
      }
      ph.method = r.Get<std::string>(*t, pre, "method", false, "a [[method]] name").value_or("");
      if (ph.kind == PhaseKind::kTraining) {
        if (ph.method.empty() && !p.methods.empty()) ph.method = p.methods.back().name;
        if (ph.method.empty())
          r.Error(t, pre + ".method",
                  "a training phase renders virtual samples and needs a [[method]]");
        else if (!p.FindMethod(ph.method))
          r.Error(t->get("method"), pre + ".method", "unknown method '" + ph.method + "'");
      } else if (t->get("method")) {
        r.Error(t->get("method"), pre + ".method", "only a training phase takes a method");
      }
      ph.duration_s = r.Get<double>(*t, pre, "duration_s", false, "a number").value_or(30);
      if (!(ph.duration_s > 0 && ph.duration_s <= 3600))
        r.Error(t->get("duration_s"), pre + ".duration_s", "expected 0 < seconds <= 3600");
      ph.same_pairs = r.Get<bool>(*t, pre, "same_pairs", false, "true or false").value_or(true);
      if (const toml::node* dp = t->get("different_pairs")) {
        if (auto n = dp->value<std::int64_t>()) {
          const auto nm = static_cast<std::int64_t>(p.materials.size());
          if (*n < 0 || *n > nm * (nm - 1) / 2)
            r.Error(dp, pre + ".different_pairs",
                    fmt::format("expected 0..{} (pairs of {} materials)", nm * (nm - 1) / 2, nm));
          else
            ph.different_pairs = static_cast<int>(*n);
        } else if (const toml::array* a = dp->as_array()) {
          for (const auto& x : *a) {
            const toml::array* pair = x.as_array();
            auto a0 = pair && pair->size() == 2 ? (*pair)[0].value<std::string>() : std::nullopt;
            auto a1 = pair && pair->size() == 2 ? (*pair)[1].value<std::string>() : std::nullopt;
            if (!a0 || !a1)
              r.Error(&x, pre + ".different_pairs",
                      "expected [\"A\", \"B\"] with two different material ids");
            else if (!ids.count(*a0) || !ids.count(*a1))
              r.Error(&x, pre + ".different_pairs",
                      fmt::format("unknown material id '{}' (the [[material]] ids are: {})",
                                  !ids.count(*a0) ? *a0 : *a1, MaterialIds(p)));
            else if (*a0 == *a1)
              r.Error(&x, pre + ".different_pairs",
                      fmt::format("a pair needs two different materials, got '{}' twice", *a0));
            else
              ph.explicit_pairs.emplace_back(*a0, *a1);
          }
        } else {
          r.Error(dp, pre + ".different_pairs",
                  "expected a count or a list of [\"A\", \"B\"] pairs");
        }
      }
      p.phases.push_back(ph);
    }
  }
  if (!has_main && !has_adaptive && !p.methods.empty())
    diag.Add(file, 0, "phase", "no [[phase]] with kind = \"main\": the methods are never shown");
  if (has_main && p.methods.empty())
    diag.Add(file, 0, "method", "a main phase needs at least one [[method]]");

  if (const toml::table* t = doc["randomization"].as_table()) {
    r.Known(*t, "randomization", {"scheme", "block_by", "no_immediate_repeat", "balance_sides"});
    const std::string scheme =
        r.Get<std::string>(*t, "randomization", "scheme", false, "full, blocked or latin-square")
            .value_or("full");
    if (scheme == "full")
      p.randomization.scheme = Scheme::kFull;
    else if (scheme == "blocked")
      p.randomization.scheme = Scheme::kBlocked;
    else if (scheme == "latin-square")
      p.randomization.scheme = Scheme::kLatinSquare;
    else
      r.Error(t->get("scheme"), "randomization.scheme",
              "expected full, blocked or latin-square, got '" + scheme + "'");
    p.randomization.block_by =
        r.Get<std::string>(*t, "randomization", "block_by", false, "method or material")
            .value_or("method");
    if (p.randomization.block_by != "method" && p.randomization.block_by != "material")
      r.Error(t->get("block_by"), "randomization.block_by", "expected method or material");
    p.randomization.no_immediate_repeat =
        r.Get<bool>(*t, "randomization", "no_immediate_repeat", false, "true or false")
            .value_or(true);
    p.randomization.balance_sides =
        r.Get<bool>(*t, "randomization", "balance_sides", false, "true or false").value_or(true);
    if (p.randomization.block_by == "material" && p.randomization.no_immediate_repeat &&
        p.randomization.scheme != Scheme::kFull)
      r.Error(t->get("block_by"), "randomization.block_by",
              "blocks by material put the same material on consecutive trials: infeasible with "
              "no_immediate_repeat");
  }
  if (const toml::table* t = doc["breaks"].as_table()) {
    r.Known(*t, "breaks", {"every_trials", "duration_s"});
    // Range-checked before the narrowing cast (4294967296 must not wrap to 0, "no breaks").
    const auto every =
        r.Get<std::int64_t>(*t, "breaks", "every_trials", false, "an integer").value_or(0);
    if (every < 0 || every > 10000)
      r.Error(t->get("every_trials"), "breaks.every_trials",
              "expected an integer 0..10000 (0: no breaks)");
    else
      p.break_every_trials = static_cast<int>(every);
    p.break_duration_s = r.Get<double>(*t, "breaks", "duration_s", false, "a number").value_or(60);
    if (!(p.break_duration_s >= 0 && p.break_duration_s <= 3600))
      r.Error(t->get("duration_s"), "breaks.duration_s", "expected 0 <= seconds <= 3600");
  }
  if (const toml::table* t = doc["masking_noise"].as_table()) {
    r.Known(*t, "masking_noise", {"enabled", "level_dB"});
    p.masking_noise =
        r.Get<bool>(*t, "masking_noise", "enabled", false, "true or false").value_or(true);
    p.masking_level_dB =
        r.Get<double>(*t, "masking_noise", "level_dB", false, "a number").value_or(70);
    // Headphone noise above 100 dB harms hearing within minutes; a finite level is required.
    if (!(p.masking_level_dB >= 0 && p.masking_level_dB <= 100))
      r.Error(t->get("level_dB"), "masking_noise.level_dB", "expected 0 <= dB <= 100");
  }
  if (const toml::table* t = doc["consent"].as_table()) ReadConsent(*t, r, &p);
  if (const toml::table* t = doc["analysis"].as_table()) {
    r.Known(*t, "analysis", {"tests", "lmm_formula", "correction"});
    // Which keywords exist is the stats module's registry's business (stats::CheckAnalyses).
    p.analyses = r.Strings(*t, "analysis", "tests", false);
    p.analyses_line = Reader::Line(t->get("tests"));
    // The formula's columns are checked when the report fits it (the stats module parses it).
    p.lmm_formula = r.Get<std::string>(*t, "analysis", "lmm_formula", false, "an lme4 formula")
                        .value_or(p.lmm_formula);
    if (p.lmm_formula.find('~') == std::string::npos ||
        p.lmm_formula.find('|') == std::string::npos)
      r.Error(t->get("lmm_formula"), "analysis.lmm_formula",
              "expected an lme4 formula 'score ~ fixed terms + (1 | participant)', got '" +
                  p.lmm_formula + "'");
    // afex's names for the sphericity correction the report judges within effects by.
    p.correction =
        r.Get<std::string>(*t, "analysis", "correction", false, "\"GG\", \"HF\" or \"none\"")
            .value_or(p.correction);
    if (p.correction != "GG" && p.correction != "HF" && p.correction != "none")
      r.Error(t->get("correction"), "analysis.correction",
              "expected \"GG\" (Greenhouse-Geisser, afex's default), \"HF\" (Huynh-Feldt) or "
              "\"none\", got '" +
                  p.correction + "'");
  } else {
    p.analyses = {"rm-anova",  "tukey",       "kruskal", "grouping",
                  "aggregate", "correlation", "shapiro"};
  }
  diag.ThrowIfAny();
  // Feasibility: plan the first participants now, so an impossible constraint set is an
  // error before any session starts.
  for (int i = 0; i < 4; ++i) Plan(p, i);
  return p;
}

Protocol LoadProtocol(const std::string& path) {
  return ParseProtocol(ReadTextFile(path, "protocol"), path);
}

}  // namespace hapticlab::protocols
