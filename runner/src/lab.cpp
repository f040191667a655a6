#include "lab.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <map>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/runner/open_rig.hpp"

namespace hapticlab::runner::internal {

namespace fs = std::filesystem;

namespace {

// Runs `load`; an input or I/O error becomes a diagnostic (in the protocol at `line`, `field`
// when the error names no file of its own).
template <typename Load>
bool Attempt(const protocols::Protocol& p, int line, const std::string& field, const Load& load,
             Diagnostics& d) {
  try {
    load();
    return true;
  } catch (const InputError& e) {
    for (const auto& x : e.diagnostics()) d.Add(x.file, x.line, x.field, x.message);
  } catch (const std::exception& e) {
    d.Add(p.file, line, field, e.what());
  }
  return false;
}

// A file the protocol names, as a diagnostic quotes it.
std::string Where(const fs::path& dir, const std::string& name) {
  return fmt::format("'{}' (looked up relative to the protocol's folder: {})", name,
                     fs::absolute(dir / name).lexically_normal().string());
}

// The profiles file (ground truth of each sample) and the observer; true when the profiles
// loaded.
bool LoadProfileFiles(const protocols::Protocol& p, const fs::path& dir, bool sim, Lab* lab,
                      Diagnostics& d) {
  if (p.profiles.empty() && sim)
    d.Add(p.file, 0, "study.profiles",
          "the simulated lab needs a profiles file (ground truth of each sample)");
  bool have_profiles = false;
  std::error_code ec;  // a path too long to look up is "no such file", not a filesystem_error
  if (!p.profiles.empty()) {
    if (!fs::is_regular_file(dir / p.profiles, ec))
      d.Add(p.file, 0, "study.profiles", "no such file " + Where(dir, p.profiles));
    else
      have_profiles = Attempt(
          p, 0, "study.profiles",
          [&] { lab->profiles = sim::LoadProfiles((dir / p.profiles).string()); }, d);
  }
  if (!p.observer.empty()) {
    if (!fs::is_regular_file(dir / p.observer, ec))
      d.Add(p.file, 0, "study.observer", "no such file " + Where(dir, p.observer));
    else
      Attempt(
          p, 0, "study.observer",
          [&] { lab->profiles.observer = sim::LoadObserver((dir / p.observer).string()); }, d);
  }
  return have_profiles;
}

// A material's model file (the protocol's, or its substitute): the model, its text and hash.
void LoadModelFile(const protocols::Protocol& p, const protocols::Material& m, const fs::path& file,
                   const fs::path& dir, Lab* lab, Diagnostics& d) {
  std::error_code ec;  // a path too long to look up is "no such file", not a filesystem_error
  if (!fs::is_regular_file(file, ec)) {
    d.Add(p.file, m.line, "material.model",
          "material '" + m.id + "': no model file " + Where(dir, m.model));
    return;
  }
  const std::string path = file.string();
  Attempt(
      p, m.line, "material.model",
      [&] {
        auto model = renderer::LoadMaterial(path);
        lab->model_texts[m.id] = ReadTextFile(path);
        lab->model_hashes[m.id] = db::HashText(lab->model_texts[m.id]);
        lab->models.emplace(m.id, std::move(model));
      },
      d);
}

// The sample's profile of a material, for the simulated lab and a placeholder model; null (with
// a diagnostic when the protocol is at fault) when there is none.
const sim::MaterialProfile* ProfileOf(const protocols::Protocol& p, const protocols::Material& m,
                                      bool sim, bool have_profiles, const Lab& lab,
                                      Diagnostics& d) {
  if (p.profiles.empty()) {
    if (!sim)
      d.Add(p.file, m.line, "material.model",
            "material '" + m.id +
                "': a placeholder model is built from the "
                "sample's profile, and the protocol names no profiles file");
    return nullptr;
  }
  if (!have_profiles) return nullptr;  // the profiles file's own problem is reported above
  const auto prof = lab.profiles.profiles.find(m.profile);
  if (prof == lab.profiles.profiles.end()) {
    d.Add(
        p.file, m.line, "material.profile",
        "material '" + m.id + "': no profile '" + m.profile + "' in " + p.profiles +
            " (its profiles: " +
            [&] {
              std::string names;
              for (const auto& [name, pr] : lab.profiles.profiles)
                names += (names.empty() ? "" : ", ") + name;
              return names.empty() ? std::string("none") : names;
            }() +
            ")");
    return nullptr;
  }
  return &prof->second;
}

}  // namespace

Lab LoadLab(const protocols::Protocol& p, const std::string& device,
            const std::map<std::string, std::string>& model_files) {
  const bool sim = IsSimulatedBackend(device);
  Lab lab;
  lab.protocol = &p;
  const fs::path dir = fs::path(p.file).parent_path();
  Diagnostics d;
  const bool have_profiles = LoadProfileFiles(p, dir, sim, &lab, d);
  // One placeholder model (and its text) per profile, however many materials share it: building
  // one takes milliseconds, and a protocol may name up to 1000 materials.
  std::map<std::string, std::pair<renderer::MaterialModel, std::string>> built;
  for (const auto& m : p.materials) {
    const auto substitute = model_files.find(m.id);
    const bool placeholder = m.model == "placeholder" && substitute == model_files.end();
    if (!placeholder) {
      LoadModelFile(p, m,
                    substitute != model_files.end() ? fs::path(substitute->second) : dir / m.model,
                    dir, &lab, d);
      if (!sim) continue;  // hardware: the fitted model is all it needs
    }
    // The simulated lab (and a placeholder model) needs the sample's profile.
    const sim::MaterialProfile* prof = ProfileOf(p, m, sim, have_profiles, lab, d);
    if (!prof) continue;
    if (placeholder) {
      auto it = built.find(m.profile);
      if (it == built.end()) {
        auto model = sim::PlaceholderModel(*prof);
        auto text = renderer::MaterialToToml(model);
        it = built.emplace(m.profile, std::pair{std::move(model), std::move(text)}).first;
      }
      lab.model_texts[m.id] = it->second.second;
      lab.model_hashes[m.id] = db::HashText(it->second.second);
      lab.models.emplace(m.id, it->second.first);
    }
  }
  d.ThrowIfAny();
  return lab;
}

Stimulus ParseStimulus(const std::string& stimulus) {
  const auto colon = stimulus.find(':');
  if (colon == std::string::npos) return {.real = false, .id = stimulus};
  return {.real = stimulus.compare(0, colon, "real") == 0, .id = stimulus.substr(colon + 1)};
}

}  // namespace hapticlab::runner::internal
