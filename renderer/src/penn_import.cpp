#include "hapticlab/renderer/penn_import.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <pugixml.hpp>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/renderer/ar.hpp"

namespace hapticlab::renderer {
namespace {

class XmlReader {
 public:
  XmlReader(std::string file, Diagnostics* d, const std::string& text) : file_(std::move(file)), d_(d) {
    // Offsets of line starts, to turn pugixml's byte offsets into line numbers.
    line_starts_.push_back(0);
    for (std::size_t i = 0; i < text.size(); ++i)
      if (text[i] == '\n') line_starts_.push_back(i + 1);
  }
  int Line(const pugi::xml_node& n) const {
    const auto off = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, n.offset_debug()));
    return static_cast<int>(std::upper_bound(line_starts_.begin(), line_starts_.end(), off) -
                            line_starts_.begin());
  }
  void Error(const pugi::xml_node& n, const std::string& field, const std::string& msg) {
    d_->Add(file_, Line(n), field, msg);
  }
  double Number(const pugi::xml_node& parent, const char* name, bool required, double def = 0) {
    const pugi::xml_node n = parent.child(name);
    if (!n) {
      if (required) Error(parent, name, "missing element; expected a number");
      return def;
    }
    return Parse(n, name);
  }
  double Parse(const pugi::xml_node& n, const std::string& field) {
    const std::string text = n.text().as_string();
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || (end && *end != '\0' && !std::isspace(static_cast<unsigned char>(*end))) ||
        !std::isfinite(v)) {
      Error(n, field, "expected a finite number, got '" + text + "'");
      return 0;
    }
    return v;
  }
  std::vector<double> Values(const pugi::xml_node& parent, const char* name, bool required) {
    std::vector<double> out;
    const pugi::xml_node n = parent.child(name);
    if (!n) {
      if (required) Error(parent, name, "missing element; expected <value> children");
      return out;
    }
    for (const auto& v : n.children("value")) out.push_back(Parse(v, name));
    return out;
  }

 private:
  std::string file_;
  Diagnostics* d_;
  std::vector<std::size_t> line_starts_;
};

// A count or index read as a double, range-checked before the narrowing cast (a value
// outside +-1e6 becomes -1, which every caller reports as out of range).
int ToInt(double x) { return x >= -1e6 && x <= 1e6 ? static_cast<int>(x) : -1; }

}  // namespace

PennImport ImportPennXml(const std::string& path) {
  pugi::xml_document doc;
  std::string text;
  {
    FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw InputError(path, 0, "", "cannot open Penn model file");
    char buf[65536];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
    std::fclose(f);
  }
  const auto res = doc.load_buffer(text.data(), text.size());
  Diagnostics diag;
  XmlReader r(path, &diag, text);
  if (!res) {
    pugi::xml_node dummy;
    const auto at = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, res.offset));
    const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(std::min(at, text.size())), '\n'));
    throw InputError(path, line, "", std::string("not well-formed XML: ") + res.description());
  }
  const pugi::xml_node set = doc.child("modelSet");
  if (!set) throw InputError(path, 1, "modelSet", "root element <modelSet> is missing");

  PennImport out;
  MaterialModel& m = out.model;
  m.source_path = path;
  m.name = set.child("material").text().as_string();
  if (m.name.empty()) r.Error(set, "material", "missing material name");
  m.friction.mu_k = r.Number(set, "mu", true);
  VibrationBank& bank = m.vibration;
  bank.sample_rate_hz = r.Number(set, "SampleRate", true, 0);
  const int num_mod = ToInt(r.Number(set, "numMod", true));
  const int num_ar = ToInt(r.Number(set, "numARCoeff", true));
  const int num_ma = ToInt(r.Number(set, "numMACoeff", false, 0));
  out.arma = num_ma > 0;
  const auto speeds_mmps = r.Values(set, "speedList", true);
  const auto forces = r.Values(set, "forceList", true);
  if (static_cast<int>(speeds_mmps.size()) != num_mod || static_cast<int>(forces.size()) != num_mod)
    r.Error(set, "speedList/forceList",
            fmt::format("expected {} entries each (numMod), found {} and {}", num_mod,
                        speeds_mmps.size(), forces.size()));
  for (const auto& tri : set.children("tri")) {
    std::array<int, 3> t{};
    int k = 0;
    bool ok = true;
    for (const auto& v : tri.children("value")) {
      const double x = r.Parse(v, "tri");
      const bool in_range = x >= 1 && x <= num_mod && x == std::floor(x);
      if (k < 3 && in_range) t[static_cast<std::size_t>(k)] = static_cast<int>(x) - 1;  // 1-based in the file
      ok = ok && in_range;
      ++k;
    }
    if (k != 3 || !ok) r.Error(tri, "tri", fmt::format("expected three 1-based model indices in 1..{}", num_mod));
    else bank.triangles.push_back(t);
  }
  for (const auto& model : set.children("model")) {
    const int idx = ToInt(r.Number(model, "modNum", true)) - 1;
    ArCell cell;
    if (idx >= 0 && idx < static_cast<int>(speeds_mmps.size()) && idx < static_cast<int>(forces.size())) {
      cell.speed_mps = speeds_mmps[static_cast<std::size_t>(idx)] * 1e-3;
      cell.force_N = forces[static_cast<std::size_t>(idx)];
    } else {
      r.Error(model, "modNum", fmt::format("expected 1..{}", num_mod));
    }
    const auto a = r.Values(model, "ARcoeff", true);
    const auto lsf = r.Values(model, "ARlsf", true);
    if (static_cast<int>(a.size()) != num_ar + 1 || a.empty() || a[0] != 1.0) {
      r.Error(model, "ARcoeff", fmt::format("expected {} values starting with 1", num_ar + 1));
      continue;
    }
    for (std::size_t i = 1; i < a.size(); ++i) cell.coeffs.push_back(-a[i]);
    if (static_cast<int>(lsf.size()) == num_ar) {
      const auto rebuilt = LsfToAr(lsf);
      for (std::size_t i = 0; i < rebuilt.size(); ++i)
        out.max_lsf_reconstruction_error =
            std::max(out.max_lsf_reconstruction_error, std::abs(rebuilt[i] - cell.coeffs[i]));
    } else {
      r.Error(model, "ARlsf", fmt::format("expected {} values", num_ar));
    }
    if (!IsStableAr(cell.coeffs)) {
      r.Error(model, "ARcoeff", "unstable AR filter");
      continue;
    }
    cell.lsf = ArToLsf(cell.coeffs);
    const double var = r.Number(model, "var", true);
    if (var < 0) r.Error(model, "var", "must be >= 0");
    if (out.arma) {
      const auto b = r.Values(model, "MAcoeff", true);
      if (static_cast<int>(b.size()) != num_ma + 1 || b.empty() || b[0] != 1.0) {
        r.Error(model, "MAcoeff", fmt::format("expected {} values starting with 1", num_ma + 1));
        continue;
      }
      cell.ma.assign(b.begin() + 1, b.end());
      std::vector<double> neg(cell.ma.size());
      for (std::size_t i = 0; i < neg.size(); ++i) neg[i] = -cell.ma[i];
      if (!IsStableAr(neg)) {
        r.Error(model, "MAcoeff", "MA part is not minimum phase; cannot interpolate in LSF form");
        continue;
      }
      cell.ma_lsf = ArToLsf(neg);
      cell.gain = r.Number(model, "gain", true, 1.0);
      // The ARMA files store var = 0 and put the amplitude in `gain`: unit excitation.
      cell.variance = var > 0 ? var : 1.0;
    } else {
      cell.variance = var;
    }
    if (idx >= 0 && static_cast<std::size_t>(idx) != bank.cells.size())
      r.Error(model, "modNum", "models must appear in modNum order 1, 2, ...");
    bank.cells.push_back(std::move(cell));
  }
  if (static_cast<int>(bank.cells.size()) != num_mod)
    r.Error(set, "model", fmt::format("numMod says {} models, found {}", num_mod, bank.cells.size()));
  diag.ThrowIfAny();
  // Penn measured speeds up to the max in the set; keep the renderer's 1 cm/s threshold.
  ValidateMaterial(m);
  return out;
}

}  // namespace hapticlab::renderer
