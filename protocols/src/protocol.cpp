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
#include "hapticlab/core/fields.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/participant_code.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "hapticlab/protocols/participant_code.hpp"
#include "protocol_fields.hpp"

namespace hapticlab::protocols {
namespace {

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
void ReadConsent(const toml::table& t, const std::string& file, Diagnostics* d, Protocol* p) {
  fields::FieldReader r(t, "consent", file, d);
  r.CheckKnown(internal::ConsentFields());
  p->consent_line = fields::FieldReader::Line(&t);
  const auto text = [&](const char* key, std::size_t max, const char* what) {
    const toml::node* n = t.get(key);
    const auto v = n ? n->value<std::string>() : std::nullopt;
    if (!n) {
      r.Error(key, std::string("missing; expected ") + what);
      return std::string();
    }
    const bool plain = v && !v->empty() && v->size() <= max &&
                       std::none_of(v->begin(), v->end(), [](unsigned char c) { return c < 0x20; });
    if (!plain)
      r.Error(key, fmt::format("expected {} (1..{} characters, one line)", what, max));
    else if ((*v)[0] == '/' || (*v)[0] == '~' || (v->size() > 1 && (*v)[1] == ':'))
      r.Error(key,
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
std::size_t Bounded(const std::string& file, Diagnostics* d, const toml::array& a,
                    const std::string& key, std::size_t max) {
  if (a.size() <= max) return a.size();
  d->Add(file, fields::FieldReader::Line(&a), key,
         fmt::format("{} entries; at most {} are allowed", a.size(), max));
  return max;
}

}  // namespace

const char* ToString(PhaseKind k) {
  const std::string_view name = NameOf(kPhaseKindNames, k);  // a literal: NUL-terminated
  return name.empty() ? "?" : name.data();
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

// True when p accepts `code`: 1-32 letters, digits, '-' or '_' matching p's pattern (then
// `why` stays empty) and the database's own rule, whatever the pattern admits
// (Anna_Kowalski_19850312; then `why` says what it refuses).
bool ParticipantCodeAccepted(const Protocol& p, const std::string& code, std::string* why) {
  // The code must be short and plain before the pattern is even tried.
  bool plain = !code.empty() && code.size() <= 32;
  for (unsigned char c : code) plain = plain && (std::isalnum(c) || c == '-' || c == '_');
  if (!plain || !RE2::FullMatch(code, RE2(p.participant_code, CodePatternOptions()))) return false;
  *why = PseudonymousCodeProblem(code);
  return why->empty();
}

void CheckParticipantCode(const Protocol& p, const std::string& code) {
  std::string why;
  if (ParticipantCodeAccepted(p, code, &why)) return;
  // An example the pattern accepts (the first code 'participant new' would hand out); none
  // when the pattern has no fixed prefix to build one from.
  std::string example;
  try {
    example = "e.g. " + NextFreeCode(p, InferCodeFormat(p), {}) + "; ";
  } catch (const InputError&) {
    // no example: the message gives the pattern alone
  }
  throw InputError(p.file, 0, "participant",
                   "'" + code + "' is not a pseudonymous code matching " + p.participant_code +
                       " (" + example +
                       "'hapticlab participant new' hands out the next free one), never a "
                       "name, birth date or phone number" +
                       (why.empty() ? "" : " (" + why + ")"));
}

namespace {

using fields::FieldReader;

// [study]: the declared keys, then the two that need code (scale, participant_code).
void ReadStudy(const toml::table& s, const std::string& file, Diagnostics* d, Protocol* p) {
  FieldReader r(s, "study", file, d);
  r.Read(internal::StudyFields(), p);
  if (p->title.empty() && !s.contains("title")) p->title = p->name;
  if (p->criteria.empty() && s.contains("criteria"))
    r.Error("criteria", "needs at least one criterion");
  if (const toml::node* sc = s.get("scale")) {
    const toml::array* a = sc->as_array();
    const auto lo = a && a->size() == 2 ? (*a)[0].value<double>() : std::nullopt;
    const auto hi = a && a->size() == 2 ? (*a)[1].value<double>() : std::nullopt;
    if (!lo || !hi || !(*lo < *hi) || !std::isfinite(*lo) || !std::isfinite(*hi)) {
      r.Error("scale", "expected [min, max] with finite min < max");
    } else {
      p->scale_min = *lo;
      p->scale_max = *hi;
    }
  }
  if (const toml::node* n = s.get("participant_code")) {
    std::string why;
    const auto pat = n->value<std::string>();
    if (!pat)
      r.Error("participant_code", "expected a regular expression");
    else if (!ValidCodePattern(*pat, &why))
      r.Error("participant_code", why);
    else
      p->participant_code = *pat;
  }
}

// The i-th table of an array of tables, or nullptr with an error.
const toml::table* TableAt(const toml::array& a, std::size_t i, const std::string& pre,
                           const std::string& file, Diagnostics* d) {
  const toml::table* t = a[i].as_table();
  if (!t) d->Add(file, FieldReader::Line(&a[i]), pre, "expected a table");
  return t;
}

// [[material]] and [[method]]: declared keys, unique names.
void ReadMaterialsAndMethods(const toml::table& doc, const std::string& file, Diagnostics* d,
                             Protocol* p) {
  std::set<std::string> ids, names;
  if (const toml::array* ms = doc["material"].as_array()) {
    for (std::size_t i = 0, n = Bounded(file, d, *ms, "material", kMaxMaterials); i < n; ++i) {
      const std::string pre = fmt::format("material[{}]", i);
      const toml::table* t = TableAt(*ms, i, pre, file, d);
      if (!t) continue;
      FieldReader r(*t, pre, file, d);
      Material m = internal::MaterialDefaults();
      m.line = FieldReader::Line(t);
      r.Read(internal::MaterialFields(), &m);
      if (!t->contains("sample")) m.sample = m.id;
      if (!t->contains("profile")) m.profile = m.id;
      if (!m.id.empty() && !ids.insert(m.id).second)
        r.Error("id", "duplicate material id '" + m.id + "'");
      p->materials.push_back(m);
    }
  }
  if (p->materials.empty()) d->Add(file, 0, "material", "at least one [[material]] is needed");
  if (const toml::array* ms = doc["method"].as_array()) {
    for (std::size_t i = 0, n = Bounded(file, d, *ms, "method", kMaxMethods); i < n; ++i) {
      const std::string pre = fmt::format("method[{}]", i);
      const toml::table* t = TableAt(*ms, i, pre, file, d);
      if (!t) continue;
      FieldReader r(*t, pre, file, d);
      Method m;
      m.line = FieldReader::Line(t);
      r.Read(internal::MethodFields(), &m);
      if (!m.name.empty() && !names.insert(m.name).second)
        r.Error("name", "duplicate method '" + m.name + "'");
      p->methods.push_back(m);
    }
  }
}

// A reference phase's different_pairs: a count of drawn pairs, or the pairs listed.
void ReadDifferentPairs(FieldReader& r, const Protocol& p, Phase* ph) {
  const toml::node* dp = r.Get("different_pairs");
  if (!dp) return;
  const auto nm = static_cast<std::int64_t>(p.materials.size());
  if (auto n = dp->value<std::int64_t>()) {
    if (*n < 0 || *n > nm * (nm - 1) / 2)
      r.Error("different_pairs",
              fmt::format("expected 0..{} (pairs of {} materials)", nm * (nm - 1) / 2, nm));
    else
      ph->different_pairs = static_cast<int>(*n);
    return;
  }
  const toml::array* a = dp->as_array();
  if (!a) {
    r.Error("different_pairs", "expected a count or a list of [\"A\", \"B\"] pairs");
    return;
  }
  for (const auto& x : *a) {
    const toml::array* pair = x.as_array();
    auto a0 = pair && pair->size() == 2 ? (*pair)[0].value<std::string>() : std::nullopt;
    auto a1 = pair && pair->size() == 2 ? (*pair)[1].value<std::string>() : std::nullopt;
    if (!a0 || !a1)
      r.ErrorAt(&x, "different_pairs", "expected [\"A\", \"B\"] with two different material ids");
    else if (!p.FindMaterial(*a0) || !p.FindMaterial(*a1))
      r.ErrorAt(&x, "different_pairs",
                fmt::format("unknown material id '{}' (the [[material]] ids are: {})",
                            !p.FindMaterial(*a0) ? *a0 : *a1, MaterialIds(p)));
    else if (*a0 == *a1)
      r.ErrorAt(&x, "different_pairs",
                fmt::format("a pair needs two different materials, got '{}' twice", *a0));
    else
      ph->explicit_pairs.emplace_back(*a0, *a1);
  }
}

// A training, reference or main [[phase]].
Phase ReadPlannedPhase(const toml::table& t, const std::string& pre, const std::string& file,
                       Diagnostics* d, const Protocol& p) {
  FieldReader r(t, pre, file, d);
  Phase ph;
  ph.line = FieldReader::Line(&t);
  r.Read(internal::PhaseFields(), &ph);
  if (ph.kind == PhaseKind::kTraining) {
    if (ph.method.empty() && !p.methods.empty()) ph.method = p.methods.back().name;
    if (ph.method.empty())
      r.ErrorAt(&t, "method", "a training phase renders virtual samples and needs a [[method]]");
    else if (!p.FindMethod(ph.method))
      r.Error("method", "unknown method '" + ph.method + "'");
  } else if (t.contains("method")) {
    r.Error("method", "only a training phase takes a method");
  }
  ReadDifferentPairs(r, p, &ph);
  return ph;
}

// [[phase]]: planned phases here, adaptive ones (staircase, quest-plus) in adaptive.cpp.
void ReadPhases(const toml::table& doc, const std::string& file, Diagnostics* d, Protocol* p) {
  bool has_main = false, has_adaptive = false;
  if (const toml::array* ps = doc["phase"].as_array()) {
    for (std::size_t i = 0, n = Bounded(file, d, *ps, "phase", kMaxPhases); i < n; ++i) {
      const std::string pre = fmt::format("phase[{}]", i);
      const toml::table* t = TableAt(*ps, i, pre, file, d);
      if (!t) continue;
      const auto k = t->get("kind") ? t->get("kind")->value<std::string>() : std::nullopt;
      if (k == "staircase" || k == "quest-plus") {
        Phase ph;
        ph.line = FieldReader::Line(t);
        ph.kind = *k == "staircase" ? PhaseKind::kStaircase : PhaseKind::kQuestPlus;
        internal::ParseAdaptivePhase(*t, pre, file, *p, d, &ph);
        has_adaptive = true;
        p->phases.push_back(ph);
        continue;
      }
      p->phases.push_back(ReadPlannedPhase(*t, pre, file, d, *p));
      has_main = has_main || p->phases.back().kind == PhaseKind::kMain;
    }
  }
  if (!has_main && !has_adaptive && !p->methods.empty())
    d->Add(file, 0, "phase", "no [[phase]] with kind = \"main\": the methods are never shown");
  if (has_main && p->methods.empty())
    d->Add(file, 0, "method", "a main phase needs at least one [[method]]");
}

// [randomization], [breaks], [masking_noise].
void ReadScheduling(const toml::table& doc, const std::string& file, Diagnostics* d, Protocol* p) {
  if (const toml::table* t = doc["randomization"].as_table()) {
    FieldReader r(*t, "randomization", file, d);
    r.Read(internal::RandomizationFields(), &p->randomization);
    const auto& rz = p->randomization;
    if (rz.block_by == "material" && rz.no_immediate_repeat && rz.scheme != Scheme::kFull)
      r.Error("block_by",
              "blocks by material put the same material on consecutive trials: infeasible with "
              "no_immediate_repeat");
  }
  if (const toml::table* t = doc["breaks"].as_table())
    FieldReader(*t, "breaks", file, d).Read(internal::BreakFields(), p);
  if (const toml::table* t = doc["masking_noise"].as_table()) {
    p->masking_noise = true;  // the table asks for it unless it says enabled = false
    FieldReader(*t, "masking_noise", file, d).Read(internal::MaskingFields(), p);
  }
}

// [analysis]: the analyses by name, the lmm formula and the sphericity correction.
void ReadAnalysis(const toml::table& doc, const std::string& file, Diagnostics* d, Protocol* p) {
  const toml::table* t = doc["analysis"].as_table();
  if (!t) {
    p->analyses = {"rm-anova",  "tukey",       "kruskal", "grouping",
                   "aggregate", "correlation", "shapiro"};
    return;
  }
  FieldReader r(*t, "analysis", file, d);
  r.Read(internal::AnalysisFields(), p);
  // Which keywords exist is the stats module's registry's business (stats::CheckAnalyses).
  if (const toml::node* tests = t->get("tests"))
    p->analyses_line = static_cast<int>(tests->source().begin.line);
  // The formula's columns are checked when the report fits it (the stats module parses it).
  if (p->lmm_formula.find('~') == std::string::npos ||
      p->lmm_formula.find('|') == std::string::npos)
    r.Error("lmm_formula",
            "expected an lme4 formula 'score ~ fixed terms + (1 | participant)', got '" +
                p->lmm_formula + "'");
  // afex's names for the sphericity correction the report judges within effects by.
  if (p->correction != "GG" && p->correction != "HF" && p->correction != "none")
    r.Error("correction",
            "expected \"GG\" (Greenhouse-Geisser, afex's default), \"HF\" (Huynh-Feldt) or "
            "\"none\", got '" +
                p->correction + "'");
}

}  // namespace

Protocol ParseProtocol(const std::string& text, const std::string& file) {
  const toml::table doc = ParseTomlText(text, file);
  Diagnostics diag;
  Protocol p;
  p.file = file;
  p.text = text;
  FieldReader(doc, "", file, &diag).CheckKnown(internal::TopLevelFields());
  if (const toml::table* s = doc["study"].as_table())
    ReadStudy(*s, file, &diag, &p);
  else
    diag.Add(file, 1, "study", "missing [study] table");
  ReadMaterialsAndMethods(doc, file, &diag, &p);
  ReadPhases(doc, file, &diag, &p);
  ReadScheduling(doc, file, &diag, &p);
  if (const toml::table* t = doc["consent"].as_table()) ReadConsent(*t, file, &diag, &p);
  ReadAnalysis(doc, file, &diag, &p);
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
