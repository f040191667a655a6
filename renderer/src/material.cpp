#include "hapticlab/renderer/material.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/fields.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/delaunay.hpp"
#include "material_fields.hpp"

namespace hapticlab::renderer {
namespace {

// Typed access to a TOML table that records every problem instead of stopping at the first.
class Reader {
 public:
  Reader(std::string file, Diagnostics* d) : file_(std::move(file)), d_(d) {}

  int Line(const toml::node* n) const { return n ? static_cast<int>(n->source().begin.line) : 0; }
  void Error(const toml::node* n, const std::string& key, const std::string& msg) {
    d_->Add(file_, Line(n), key, msg);
  }

  std::optional<double> Number(const toml::table& t, const std::string& prefix,
                               const std::string& key, bool required) {
    const toml::node* n = t.get(key);
    const std::string full = prefix.empty() ? key : prefix + "." + key;
    if (!n) {
      if (required) d_->Add(file_, Line(&t), full, "missing; expected a number");
      return std::nullopt;
    }
    if (auto v = n->value<double>()) {
      if (!std::isfinite(*v)) {
        Error(n, full, "must be finite");
        return std::nullopt;
      }
      return v;
    }
    Error(n, full, "expected a number");
    return std::nullopt;
  }

  std::optional<std::string> String(const toml::table& t, const std::string& prefix,
                                    const std::string& key, bool required) {
    const toml::node* n = t.get(key);
    const std::string full = prefix.empty() ? key : prefix + "." + key;
    if (!n) {
      if (required) d_->Add(file_, Line(&t), full, "missing; expected a string");
      return std::nullopt;
    }
    if (auto v = n->value<std::string>()) return v;
    Error(n, full, "expected a string");
    return std::nullopt;
  }

  std::vector<double> Numbers(const toml::table& t, const std::string& prefix,
                              const std::string& key, bool required) {
    const toml::node* n = t.get(key);
    const std::string full = prefix.empty() ? key : prefix + "." + key;
    std::vector<double> out;
    if (!n) {
      if (required) d_->Add(file_, Line(&t), full, "missing; expected an array of numbers");
      return out;
    }
    const auto* arr = n->as_array();
    if (!arr) {
      Error(n, full, "expected an array of numbers");
      return out;
    }
    for (std::size_t i = 0; i < arr->size(); ++i) {
      auto v = (*arr)[i].value<double>();
      if (!v || !std::isfinite(*v)) {
        Error(&(*arr)[i], fmt::format("{}[{}]", full, i), "expected a finite number");
        continue;
      }
      out.push_back(*v);
    }
    return out;
  }

  const std::string& file() const { return file_; }
  Diagnostics& diag() { return *d_; }

 private:
  std::string file_;
  Diagnostics* d_;
};

// One [[vibration.cells]] table: its AR part (order 1..kMaxArOrder, stable, and the stored LSFs
// when given describing the same filter) and MA part (minimum phase).
ArCell ReadCell(Reader& r, const toml::table& c, const std::string& prefix) {
  ArCell cell;
  fields::FieldReader(c, prefix, r.file(), &r.diag()).Read(internal::CellFields(), &cell);
  const int line = r.Line(&c);
  if (cell.coeffs.empty() || cell.coeffs.size() > static_cast<std::size_t>(kMaxArOrder)) {
    r.diag().Add(r.file(), line, prefix + ".ar", fmt::format("order must be 1..{}", kMaxArOrder));
  } else if (!IsStableAr(cell.coeffs)) {
    r.diag().Add(r.file(), line, prefix + ".ar",
                 "unstable AR filter (a root of A(z) on or outside the unit circle)");
  } else {
    cell.lsf = ArToLsf(cell.coeffs);
    // Stored LSFs (written by fit-vibration) must describe the same filter.
    const auto stored = r.Numbers(c, prefix, "lsf", false);
    if (!stored.empty()) {
      bool same = stored.size() == cell.lsf.size();
      for (std::size_t k = 0; same && k < stored.size(); ++k)
        same = std::abs(stored[k] - cell.lsf[k]) < 1e-6;
      if (!same)
        r.diag().Add(r.file(), line, prefix + ".lsf",
                     "does not match the AR coefficients of the cell");
    }
  }
  if (!cell.ma.empty()) {
    std::vector<double> neg(cell.ma.size());
    for (std::size_t k = 0; k < neg.size(); ++k) neg[k] = -cell.ma[k];
    if (cell.ma.size() > static_cast<std::size_t>(kMaxArOrder) || !IsStableAr(neg))
      r.diag().Add(
          r.file(), line, prefix + ".ma",
          "MA part must have order <= 64 and be minimum phase (roots inside the unit circle)");
    else
      cell.ma_lsf = ArToLsf(neg);
  }
  return cell;
}

// vibration.triangles: each [i, j, k] three 0-based indices of the bank's cells.
void ReadTriangles(Reader& r, const toml::node* tri, VibrationBank* bank) {
  const toml::array* arr = tri->as_array();
  if (!arr) r.Error(tri, "vibration.triangles", "expected an array of [i, j, k]");
  for (std::size_t i = 0; arr && i < arr->size(); ++i) {
    const toml::array* one = (*arr)[i].as_array();
    std::array<int, 3> idx{};
    bool ok = one && one->size() == 3;
    for (std::size_t k = 0; ok && k < 3; ++k) {
      auto v = (*one)[k].value<std::int64_t>();
      ok = v && *v >= 0 && *v < static_cast<std::int64_t>(bank->cells.size());
      if (ok) idx[k] = static_cast<int>(*v);
    }
    if (!ok)
      r.Error(&(*arr)[i], fmt::format("vibration.triangles[{}]", i),
              fmt::format("expected three 0-based cell indices below {}", bank->cells.size()));
    else
      bank->triangles.push_back(idx);
  }
}

void ReadVibration(Reader& r, const toml::table& t, const std::filesystem::path& base,
                   VibrationBank* bank, int depth);

void ReadVibrationFile(Reader& r, const toml::node* at, const std::filesystem::path& path,
                       VibrationBank* bank, int depth) {
  if (depth > 2) {
    r.Error(at, "vibration.file", "vibration files nest too deeply");
    return;
  }
  toml::table doc;
  try {
    doc = ParseTomlFile(path.string(), "vibration file");
  } catch (const InputError& e) {  // collected with the including file's other problems
    for (const Diagnostic& d : e.diagnostics()) r.diag().Add(d.file, d.line, d.field, d.message);
    return;
  }
  Diagnostics inner;
  Reader ri(path.string(), &inner);
  const toml::table* vt = doc["vibration"].as_table();
  if (!vt)
    inner.Add(path.string(), 0, "vibration", "missing [vibration] table");
  else
    ReadVibration(ri, *vt, path.parent_path(), bank, depth + 1);
  for (const auto& d : inner.items()) r.diag().Add(d.file, d.line, d.field, d.message);
}

void ReadVibration(Reader& r, const toml::table& t, const std::filesystem::path& base,
                   VibrationBank* bank, int depth) {
  fields::FieldReader fr(t, "vibration", r.file(), &r.diag());
  if (t.contains("file")) {  // the bank lives in a file of its own
    fr.CheckKnown(internal::VibrationFields());
    if (auto f = r.String(t, "vibration", "file", false))
      ReadVibrationFile(r, t.get("file"), base / *f, bank, depth);
    return;
  }
  fr.Read(internal::VibrationFields(), bank);
  if (!(bank->max_speed_mps == 0 || bank->max_speed_mps > kSaturationMarginSpeed_mps))
    fr.Error("max_speed_mps",
             fmt::format("must be 0 (no limit) or > {:g}", kSaturationMarginSpeed_mps));
  if (!(bank->max_force_N == 0 || bank->max_force_N > kSaturationMarginForce_N))
    fr.Error("max_force_N",
             fmt::format("must be 0 (no limit) or > {:g}", kSaturationMarginForce_N));
  const toml::node* cells_node = t.get("cells");
  const toml::array* cells = cells_node ? cells_node->as_array() : nullptr;
  if (!cells) {
    r.Error(&t, "vibration.cells", "missing; expected [[vibration.cells]] tables");
    return;
  }
  for (std::size_t i = 0; i < cells->size(); ++i) {
    const std::string prefix = fmt::format("vibration.cells[{}]", i);
    const toml::table* c = (*cells)[i].as_table();
    if (!c) {
      r.Error(&(*cells)[i], prefix, "expected a table");
      continue;
    }
    ArCell cell = ReadCell(r, *c, prefix);
    bank->cells.push_back(std::move(cell));
  }
  if (const toml::node* tri = t.get("triangles")) ReadTriangles(r, tri, bank);
}

// [geometry]: a height-map file, a sine or flat (keys declared in material_fields.cpp).
void ReadGeometry(Reader& r, const toml::table& t, const std::filesystem::path& base,
                  MaterialModel* m) {
  const toml::table* g = &t;
  const std::string& name = r.file();
  Diagnostics& diag = r.diag();
  fields::FieldReader(*g, "geometry", name, &diag).CheckKnown(internal::GeometryFields());
  const std::string kind =
      r.String(*g, "geometry", "kind", false).value_or(g->contains("file") ? "file" : "flat");
  if (kind == "file") {
    const auto file = r.String(*g, "geometry", "file", true);
    const auto w = r.Number(*g, "geometry", "width", true);
    const auto h = r.Number(*g, "geometry", "height", true);
    const auto p = r.Number(*g, "geometry", "pitch_m", true);
    if (p && !(*p > 0 && *p <= 0.01))
      r.Error(g->get("pitch_m"), "geometry.pitch_m", "must be in (0, 0.01] m");
    // Range-checked before the narrowing cast; the file's size is checked by LoadRawF32.
    constexpr double kMaxSide = 1 << 20;  // samples along one side
    bool sides_ok = true;
    for (const auto& [key, v] : {std::pair{"width", w}, std::pair{"height", h}})
      if (v && !(*v >= 1 && *v <= kMaxSide && *v == std::floor(*v))) {
        r.Error(g->get(key), std::string("geometry.") + key,
                "must be a whole number of samples in 1..1048576");
        sides_ok = false;
      }
    if (file && w && h && p && *p > 0 && sides_ok) {
      try {
        m->geometry = std::make_shared<HeightMap>(HeightMap::LoadRawF32(
            (base / *file).string(), static_cast<int>(*w), static_cast<int>(*h), *p));
      } catch (const InputError& e) {
        for (const auto& d : e.diagnostics()) diag.Add(d.file, d.line, d.field, d.message);
        diag.Add(name, r.Line(g->get("file")), "geometry.file", "height map could not be loaded");
      }
    }
  } else if (kind == "sine") {
    const auto a = r.Number(*g, "geometry", "amplitude_m", true);
    const auto l = r.Number(*g, "geometry", "wavelength_m", true);
    if (a && l) {
      if (!(*a >= 0 && *a <= 0.01 && *l > 0 && *l <= 1))
        r.Error(g, "geometry", "amplitude_m must be in [0, 0.01] m and wavelength_m in (0, 1] m");
      else
        m->geometry = std::make_shared<HeightMap>(HeightMap::Sine(*a, *l, *a));
    }
  } else if (kind != "flat") {
    r.Error(g->get("kind"), "geometry.kind", "expected \"file\", \"sine\" or \"flat\"");
  }
}

// Scattered cells without a triangulation: compute the Delaunay triangulation.
void TriangulateScattered(const std::string& name, Diagnostics* diag, VibrationBank* bank) {
  auto& vb = *bank;
  if (vb.cells.size() >= 3 && vb.grid_speeds_mps.empty() && vb.grid_forces_N.empty() &&
      vb.triangles.empty()) {
    std::vector<double> xs, ys;
    for (const auto& c : vb.cells) {
      xs.push_back(c.speed_mps);
      ys.push_back(c.force_N);
    }
    const auto [x0, x1] = std::minmax_element(xs.begin(), xs.end());
    const auto [y0, y1] = std::minmax_element(ys.begin(), ys.end());
    if (!(*x1 > *x0) || !(*y1 > *y0)) {
      diag->Add(name, 0, "vibration.cells",
                "cells spread over both speed and force (a triangulation needs them)");
    } else {
      try {
        vb.triangles = DelaunayTriangulate(xs, ys);
      } catch (const std::runtime_error& e) {
        diag->Add(name, 0, "vibration.cells", e.what());
      }
    }
  }
}

}  // namespace

MaterialModel ParseMaterial(const std::string& text, const std::string& name) {
  const toml::table doc = ParseTomlText(text, name);
  Diagnostics diag;
  Reader r(name, &diag);
  const auto base = std::filesystem::path(name).parent_path();
  MaterialModel m;
  m.source_path = name;
  fields::FieldReader(doc, "", name, &diag).Read(internal::TopLevelFields(), &m);
  if (const toml::table* c = doc["contact"].as_table())
    fields::FieldReader(*c, "contact", name, &diag).Read(internal::ContactFields(), &m.contact);
  else
    diag.Add(name, 0, "contact", "missing [contact] table");
  if (const toml::table* f = doc["friction"].as_table())
    fields::FieldReader(*f, "friction", name, &diag).Read(internal::FrictionFields(), &m.friction);
  else
    diag.Add(name, 0, "friction", "missing [friction] table");
  if (const toml::table* g = doc["geometry"].as_table()) ReadGeometry(r, *g, base, &m);
  if (const toml::table* v = doc["vibration"].as_table())
    ReadVibration(r, *v, base, &m.vibration, 0);
  TriangulateScattered(name, &diag, &m.vibration);
  if (const toml::table* nt = doc["neural"].as_table()) {
    fields::FieldReader(*nt, "neural", name, &diag).Read(internal::NeuralFields(), &m);
    if (const std::string& file = m.neural_file; !file.empty()) {
      const auto p =
          std::filesystem::path(file).is_absolute() ? std::filesystem::path(file) : base / file;
      try {
        m.neural = std::make_shared<NeuralModel>(LoadNeuralModel(p.string()));
      } catch (const InputError& e) {
        for (const auto& x : e.diagnostics()) diag.Add(x.file, x.line, x.field, x.message);
        diag.Add(name, r.Line(nt->get("file")), "neural.file",
                 "the neural model could not be loaded");
      }
    }
  }
  if (const toml::table* h = doc["hybrid"].as_table()) {
    fields::FieldReader(*h, "hybrid", name, &diag).Read(internal::HybridFields(), &m);
  }
  diag.ThrowIfAny();
  ValidateMaterial(m);
  return m;
}

MaterialModel LoadMaterial(const std::string& path) {
  return ParseMaterial(ReadTextFile(path, "material model"), path);
}

std::string MaterialToToml(const MaterialModel& m, const std::string& geometry_file) {
  std::string s;
  s += fmt::format("name = \"{}\"\n", m.name);
  s += "effects = [";
  for (std::size_t i = 0; i < m.effects.size(); ++i)
    s += fmt::format("{}\"{}\"", i ? ", " : "", m.effects[i]);
  s += "]\n\n[contact]\n";
  s += fmt::format(
      "texture_K = {:.17g}  # N/m^n\ntexture_B = {:.17g}  # N s/m^(n+1)\ntexture_n = {:.17g}\n",
      m.contact.texture.K, m.contact.texture.B, m.contact.texture.n);
  s += fmt::format("base_model = \"{}\"\nbase_K = {:.17g}\nbase_B = {:.17g}\nbase_n = {:.17g}\n",
                   m.contact.base_model == BaseModel::kLinear ? "linear" : "hunt-crossley",
                   m.contact.base.K, m.contact.base.B, m.contact.base.n);
  s += fmt::format("layer_thickness_m = {:.17g}\n\n[friction]\n", m.contact.layer_thickness_m);
  s += fmt::format("kappa_N_per_m = {:.17g}\nmu_k = {:.17g}\nmu_b_Ns_per_m = {:.17g}\n\n",
                   m.friction.kappa_N_per_m, m.friction.mu_k, m.friction.mu_b_Ns_per_m);
  if (!geometry_file.empty() && m.geometry) {
    s += fmt::format(
        "[geometry]\nkind = \"file\"\nfile = \"{}\"\nwidth = {}\nheight = {}\npitch_m = "
        "{:.17g}\n\n",
        geometry_file, m.geometry->width(), m.geometry->height(), m.geometry->pitch_m());
  } else {
    s += "[geometry]\nkind = \"flat\"\n\n";
  }
  s += fmt::format("[hybrid]\ncutoff_hz = {:.17g}\n", m.hybrid_cutoff_hz);
  if (!m.neural_file.empty()) s += fmt::format("\n[neural]\nfile = \"{}\"\n", m.neural_file);
  const auto& b = m.vibration;
  if (!b.empty()) {
    s += fmt::format("\n[vibration]\nsample_rate_hz = {:.17g}\nmin_speed_mps = {:.17g}\n",
                     b.sample_rate_hz, b.min_speed_mps);
    if (b.max_speed_mps > 0) s += fmt::format("max_speed_mps = {:.17g}\n", b.max_speed_mps);
    if (b.max_force_N > 0) s += fmt::format("max_force_N = {:.17g}\n", b.max_force_N);
    if (b.light_force_N > 0) s += fmt::format("light_force_N = {:.17g}\n", b.light_force_N);
    auto list = [](const std::vector<double>& v) {
      std::string o = "[";
      for (std::size_t i = 0; i < v.size(); ++i) o += fmt::format("{}{:.17g}", i ? ", " : "", v[i]);
      return o + "]";
    };
    if (!b.grid_speeds_mps.empty()) {
      s += "speeds_mps = " + list(b.grid_speeds_mps) + "\n";
      s += "forces_N = " + list(b.grid_forces_N) + "\n";
    }
    if (!b.triangles.empty()) {
      s += "triangles = [";
      for (std::size_t i = 0; i < b.triangles.size(); ++i)
        s += fmt::format("{}[{}, {}, {}]", i ? ", " : "", b.triangles[i][0], b.triangles[i][1],
                         b.triangles[i][2]);
      s += "]\n";
    }
    for (const auto& c : b.cells) {
      s += fmt::format(
          "\n[[vibration.cells]]\nspeed_mps = {:.17g}\nforce_N = {:.17g}\nvariance = {:.17g}\n",
          c.speed_mps, c.force_N, c.variance);
      s += "ar = " + list(c.coeffs) + "\n";
      if (!c.lsf.empty()) s += "lsf = " + list(c.lsf) + "  # rad/sample, derived from ar\n";
      if (!c.ma.empty()) s += "ma = " + list(c.ma) + fmt::format("\ngain = {:.17g}\n", c.gain);
    }
  }
  return s;
}

}  // namespace hapticlab::renderer
