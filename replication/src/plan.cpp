// Reading a plan back: verified files, then the analysis plan.

#include "hapticlab/replication/plan.hpp"

#include <fmt/format.h>

#include <filesystem>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "plan_internal.hpp"

namespace hapticlab::replication {
namespace {

namespace fs = std::filesystem;

// Reads string / string-array / number keys of one table, each problem collected in `d`.
struct Reader {
  const toml::table& t;
  std::string file, table;
  Diagnostics* d;
  int Line(const char* key) const {
    const auto* n = t.get(key);
    return n ? static_cast<int>(n->source().begin.line) : 0;
  }
  std::string Str(const char* key, bool required = true) const {
    if (const auto v = t[key].value<std::string>()) return *v;
    if (required || t.contains(key))
      d->Add(file, Line(key), table + "." + key, "expected a string");
    return "";
  }
  std::vector<std::string> List(const char* key) const {
    std::vector<std::string> out;
    const auto* a = t[key].as_array();
    if (!a) {
      d->Add(file, Line(key), table + "." + key, "expected an array of strings");
      return out;
    }
    for (const auto& e : *a) {
      if (const auto v = e.value<std::string>())
        out.push_back(*v);
      else
        d->Add(file, Line(key), table + "." + key, "expected an array of strings");
    }
    return out;
  }
  double Num(const char* key, double fallback) const {
    if (!t.contains(key)) return fallback;
    if (const auto v = t[key].value<double>()) return *v;
    d->Add(file, Line(key), table + "." + key, "expected a number");
    return fallback;
  }
};

}  // namespace

AnalysisPlan ParseAnalysisPlan(const std::string& text, const std::string& file) {
  const auto doc = ParseTomlText(text, file);
  Diagnostics d;
  AnalysisPlan a;
  static const toml::table kEmpty;
  const auto table = [&](const char* name) -> const toml::table& {
    if (const auto* t = doc[name].as_table()) return *t;
    d.Add(file, 0, name, "missing table [" + std::string(name) + "]");
    return kEmpty;
  };
  const Reader plan{table("plan"), file, "plan", &d};
  a.study = plan.Str("study");
  a.protocol_file = plan.Str("protocol");
  a.protocol_canonical_sha256 = plan.Str("protocol_canonical_sha256");
  a.software = plan.Str("software", false);
  if (!a.protocol_file.empty() && !internal::SafeRelativePath(a.protocol_file))
    d.Add(file, plan.Line("protocol"), "plan.protocol",
          "expected a path inside the plan directory, got '" + a.protocol_file + "'");
  const Reader an{table("analysis"), file, "analysis", &d};
  a.tests = an.List("tests");
  a.exclusions = an.List("exclusions");
  a.correction = an.Str("correction");
  a.lmm_formula = an.Str("lmm_formula");
  a.alpha = an.Num("alpha", 0.05);
  a.primary_criterion = an.Str("primary_criterion");
  a.primary_effect = an.Str("primary_effect");
  if (const auto* models = doc["model"].as_array()) {
    for (const auto& m : *models) {
      const auto* t = m.as_table();
      if (!t) {
        d.Add(file, 0, "model", "expected [[model]] tables");
        continue;
      }
      const Reader r{*t, file, "model", &d};
      a.models.push_back({r.Str("material"), r.Str("file"), r.Str("sha256"), r.Str("source")});
    }
  }
  if (const auto* p = doc["power"].as_table()) {
    const Reader r{*p, file, "power", &d};
    a.power = true;
    a.power_observer = r.Str("observer");
    a.power_observer_sha256 = r.Str("observer_sha256", false);
    a.power_participants_needed = static_cast<int>(r.Num("participants_needed", 0));
  }
  d.ThrowIfAny();
  return a;
}

Plan ReadPlan(const std::string& dir) {
  const auto v = VerifyPlan(dir);
  if (!v.ok()) {
    Diagnostics d;
    for (const auto& p : v.problems) d.Add((fs::path(dir) / p.path).string(), 0, p.kind, p.detail);
    d.ThrowIfAny();
  }
  Plan p;
  p.dir = dir;
  p.plan_hash = v.plan_hash;
  const std::string ap = (fs::path(dir) / kAnalysisPlanFile).string();
  p.analysis = ParseAnalysisPlan(ReadTextFile(ap, "analysis plan"), ap);
  p.protocol_path = (fs::path(dir) / p.analysis.protocol_file).string();
  p.protocol_text = ReadTextFile(p.protocol_path, "the plan's protocol");
  return p;
}

}  // namespace hapticlab::replication
