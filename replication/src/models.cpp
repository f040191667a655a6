// The files and material models of a protocol (models_internal.hpp).

#include <filesystem>
#include <optional>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/sim/sim_lab.hpp"
#include "models_internal.hpp"
#include "plan_internal.hpp"

namespace hapticlab::replication::internal {
namespace {

namespace fs = std::filesystem;

// The path `name` (relative to `base`, itself relative to the protocol's folder) normalised;
// "" when it leaves the folder.
std::string Inside(const fs::path& base, const std::string& name) {
  if (fs::path(name).is_absolute()) return "";
  const auto p = (base / name).lexically_normal().generic_string();
  return SafeRelativePath(p) ? p : "";
}

// Adds `rel` (relative to the protocol's folder `dir`) and, for a TOML model or vibration
// file, the files it names (geometry.file, vibration.file, neural.file), `depth` levels deep.
void AddFile(const protocols::Protocol& p, const fs::path& dir, const std::string& rel,
             const std::string& key, int line, int depth, std::map<std::string, std::string>* out,
             Diagnostics* d) {
  if (out->count("protocol/" + rel)) return;
  std::string text;
  try {
    text = ReadTextFile((dir / rel).string(), key);
  } catch (const InputError& e) {
    d->Add(p.file, line, key, e.what());
    return;
  }
  (*out)["protocol/" + rel] = text;
  if (depth > 3 || fs::path(rel).extension() != ".toml" || key == "study.profiles" ||
      key == "study.observer")
    return;
  toml::table doc;
  try {
    doc = ParseTomlText(text, (dir / rel).string());
  } catch (const InputError&) {
    return;  // the model's own loader reports it
  }
  for (const char* table : {"geometry", "vibration", "neural"})
    if (const auto f = doc[table]["file"].value<std::string>()) {
      const auto inner = Inside(fs::path(rel).parent_path(), *f);
      if (inner.empty())
        d->Add((dir / rel).string(), 0, std::string(table) + ".file",
               "a plan holds the files a model names: expected a path inside the protocol's "
               "folder, got '" +
                   *f + "'");
      else
        AddFile(p, dir, inner, key, line, depth + 1, out, d);
    }
}

}  // namespace

std::map<std::string, std::string> ProtocolFiles(const protocols::Protocol& p) {
  const fs::path dir = fs::path(p.file).parent_path();
  std::map<std::string, std::string> out;
  out["protocol/" + fs::path(p.file).filename().string()] = p.text;
  Diagnostics d;
  const auto add = [&](const std::string& name, const std::string& key, int line) {
    const auto rel = Inside(".", name);
    if (rel.empty())
      d.Add(p.file, line, key,
            "a plan holds the files a protocol names: expected a path inside the protocol's "
            "folder (no '..', not absolute), got '" +
                name + "'");
    else
      AddFile(p, dir, rel, key, line, 0, &out, &d);
  };
  if (!p.profiles.empty()) add(p.profiles, "study.profiles", 0);
  if (!p.observer.empty()) add(p.observer, "study.observer", 0);
  for (const auto& m : p.materials)
    if (m.model != "placeholder") add(m.model, "material.model", m.line);
  d.ThrowIfAny();
  return out;
}

std::vector<ModelText> ModelsOf(const protocols::Protocol& p) {
  const fs::path dir = fs::path(p.file).parent_path();
  std::vector<ModelText> out;
  std::optional<sim::ProfileSet> profiles;
  std::map<std::string, int> used;  // file names given, for unique ones
  for (const auto& m : p.materials) {
    ModelText t;
    t.material = m.id;
    std::string name = SafeName(m.id);
    if (used[name]++) name += "-" + std::to_string(used[name]);
    t.plan_file = "models/" + name + ".toml";
    if (m.model != "placeholder") {
      const auto path = (dir / m.model).string();
      (void)renderer::LoadMaterial(path);  // as the runner checks it
      t.text = ReadTextFile(path, "material model");
      t.source = "protocol/" + Inside(".", m.model);
    } else {
      if (p.profiles.empty())
        throw InputError(p.file, m.line, "material.model",
                         "material '" + m.id +
                             "': a placeholder model is built from the sample's profile, and "
                             "the protocol names no profiles file");
      if (!profiles) profiles = sim::LoadProfiles((dir / p.profiles).string());
      const auto it = profiles->profiles.find(m.profile);
      if (it == profiles->profiles.end())
        throw InputError(
            p.file, m.line, "material.profile",
            "material '" + m.id + "': no profile '" + m.profile + "' in " + p.profiles);
      t.text = renderer::MaterialToToml(sim::PlaceholderModel(it->second));
      t.source = "placeholder built from profile '" + m.profile + "' of protocol/" +
                 Inside(".", p.profiles);
    }
    t.sha256 = db::HashText(t.text);
    out.push_back(std::move(t));
  }
  return out;
}

}  // namespace hapticlab::replication::internal
