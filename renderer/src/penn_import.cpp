#include "hapticlab/renderer/penn_import.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <pugixml.hpp>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/renderer/ar.hpp"

namespace hapticlab::renderer {
namespace {

class XmlReader {
 public:
  XmlReader(std::string file, Diagnostics* d, const std::string& text)
      : file_(std::move(file)), d_(d) {
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
  // An integer element in [lo, hi] (checked before any conversion to int).
  int Integer(const pugi::xml_node& parent, const char* name, bool required, int lo, int hi,
              int def) {
    const pugi::xml_node n = parent.child(name);
    if (!n) {
      if (required)
        Error(parent, name, fmt::format("missing element; expected an integer in {}..{}", lo, hi));
      return def;
    }
    const double v = Parse(n, name);
    if (!(v >= lo && v <= hi && v == std::floor(v))) {
      Error(n, name,
            fmt::format("expected an integer in {}..{}, got '{}'", lo, hi, n.text().as_string()));
      return def;
    }
    return static_cast<int>(v);
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

// The whole file (ImportPennXml parses the buffer, so offsets map to lines).
std::string ReadWholeFile(const std::string& path) {
  std::string text;
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path, 0, "", "cannot open Penn model file");
  char buf[65536];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
  std::fclose(f);
  return text;
}

// The modelled range (mm/s, N): the toolkit saturates speed and force just inside it.
void ReadRange(XmlReader& r, const pugi::xml_node& set, VibrationBank& bank) {
  if (set.child("maxSpeed")) {
    const double v = r.Number(set, "maxSpeed", true);
    if (!(v * 1e-3 > kSaturationMarginSpeed_mps))
      r.Error(set.child("maxSpeed"), "maxSpeed", "must be > 0.01 mm/s");
    else
      bank.max_speed_mps = v * 1e-3;
  }
  if (set.child("maxForce")) {
    const double v = r.Number(set, "maxForce", true);
    if (!(v > kSaturationMarginForce_N))
      r.Error(set.child("maxForce"), "maxForce", "must be > 0.01 N");
    else
      bank.max_force_N = v;
  }
}

void ReadTriangles(XmlReader& r, const pugi::xml_node& set, int num_mod, VibrationBank& bank) {
  for (const auto& tri : set.children("tri")) {
    std::array<int, 3> t{};
    int k = 0;
    bool ok = true;
    for (const auto& v : tri.children("value")) {
      const double x = r.Parse(v, "tri");
      const bool in_range =
          x >= 1 && x <= num_mod && x == std::floor(x);  // checked before the cast
      if (k < 3 && in_range)
        t[static_cast<std::size_t>(k)] = static_cast<int>(x) - 1;  // 1-based in the file
      ok = ok && in_range;
      ++k;
    }
    if (k != 3 || !ok)
      r.Error(tri, "tri", fmt::format("expected three 1-based model indices in 1..{}", num_mod));
    else
      bank.triangles.push_back(t);
  }
}

struct ModelSetShape {
  int num_mod = 0, num_ar = 0, num_ma = 0;
  std::vector<double> speeds_mmps, forces;  ///< per model (modNum order)
};

// The MA part of an ARMA model into `cell`; false (reported) when it cannot be used.
bool ReadMaPart(XmlReader& r, const pugi::xml_node& model, int num_ma, ArCell& cell) {
  const auto b = r.Values(model, "MAcoeff", true);
  if (static_cast<int>(b.size()) != num_ma + 1 || b.empty() || b[0] != 1.0) {
    r.Error(model, "MAcoeff", fmt::format("expected {} values starting with 1", num_ma + 1));
    return false;
  }
  cell.ma.assign(b.begin() + 1, b.end());
  std::vector<double> neg(cell.ma.size());
  for (std::size_t i = 0; i < neg.size(); ++i) neg[i] = -cell.ma[i];
  if (!IsStableAr(neg)) {
    r.Error(model, "MAcoeff", "MA part is not minimum phase; cannot interpolate in LSF form");
    return false;
  }
  cell.ma_lsf = ArToLsf(neg);
  cell.gain = r.Number(model, "gain", true, 1.0);
  return true;
}

// One <model> as a cell of the bank; nullopt (reported) when it cannot be used. `idx` is its
// 0-based modNum.
std::optional<ArCell> ReadModel(XmlReader& r, const pugi::xml_node& model,
                                const ModelSetShape& shape, PennImport& out, int& idx) {
  idx = r.Integer(model, "modNum", true, 1, std::max(1, shape.num_mod), 0) - 1;
  ArCell cell;
  if (idx >= 0 && idx < static_cast<int>(shape.speeds_mmps.size()) &&
      idx < static_cast<int>(shape.forces.size())) {
    cell.speed_mps = shape.speeds_mmps[static_cast<std::size_t>(idx)] * 1e-3;
    cell.force_N = shape.forces[static_cast<std::size_t>(idx)];
  }  // else: Integer() or the speedList/forceList check has reported it
  const auto a = r.Values(model, "ARcoeff", true);
  const auto lsf = r.Values(model, "ARlsf", true);
  if (static_cast<int>(a.size()) != shape.num_ar + 1 || a.empty() || a[0] != 1.0) {
    r.Error(model, "ARcoeff", fmt::format("expected {} values starting with 1", shape.num_ar + 1));
    return std::nullopt;
  }
  for (std::size_t i = 1; i < a.size(); ++i) cell.coeffs.push_back(-a[i]);
  if (static_cast<int>(lsf.size()) == shape.num_ar) {
    const auto rebuilt = LsfToAr(lsf);
    for (std::size_t i = 0; i < rebuilt.size(); ++i)
      out.max_lsf_reconstruction_error =
          std::max(out.max_lsf_reconstruction_error, std::abs(rebuilt[i] - cell.coeffs[i]));
  } else {
    r.Error(model, "ARlsf", fmt::format("expected {} values", shape.num_ar));
  }
  if (!IsStableAr(cell.coeffs)) {
    r.Error(model, "ARcoeff", "unstable AR filter");
    return std::nullopt;
  }
  cell.lsf = ArToLsf(cell.coeffs);
  const double var = r.Number(model, "var", true);
  if (var < 0) r.Error(model, "var", "must be >= 0");
  if (out.arma && !ReadMaPart(r, model, shape.num_ma, cell)) return std::nullopt;
  // Excitation variance as stored, for both variants: the toolkit drives every model with
  // N(0, var) noise (ARMA: times `gain`), so its var = 0 boundary models are silent.
  cell.variance = var;
  return cell;
}

// A triangle whose vertices are collinear or repeated cannot weight a point.
void CheckTriangles(XmlReader& r, const pugi::xml_node& set, const VibrationBank& bank,
                    int num_mod) {
  for (const auto& t : bank.triangles) {
    const auto& a = bank.cells[static_cast<std::size_t>(t[0])];
    const auto& b = bank.cells[static_cast<std::size_t>(t[1])];
    const auto& c = bank.cells[static_cast<std::size_t>(t[2])];
    const double det = (b.speed_mps - a.speed_mps) * (c.force_N - a.force_N) -
                       (c.speed_mps - a.speed_mps) * (b.force_N - a.force_N);
    if (det == 0)
      r.Error(set, "tri",
              fmt::format("triangle {} {} {} (1-based) has no area", t[0] + 1, t[1] + 1, t[2] + 1));
  }
  if (num_mod > 1 && bank.triangles.empty())
    r.Error(set, "tri", "no triangles: the models cannot be interpolated");
}

}  // namespace

PennImport ImportPennXml(const std::string& path) {
  pugi::xml_document doc;
  const std::string text = ReadWholeFile(path);
  const auto res = doc.load_buffer(text.data(), text.size());
  Diagnostics diag;
  XmlReader r(path, &diag, text);
  if (!res) {
    const auto at = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, res.offset));
    const int line =
        1 + static_cast<int>(std::count(
                text.begin(), text.begin() + static_cast<std::ptrdiff_t>(std::min(at, text.size())),
                '\n'));
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
  // Bounds: a model set never holds more than 100000 models; filters run up to kMaxArOrder.
  ModelSetShape shape;
  shape.num_mod = r.Integer(set, "numMod", true, 1, 100000, 0);
  shape.num_ar = r.Integer(set, "numARCoeff", true, 1, kMaxArOrder, 0);
  shape.num_ma = r.Integer(set, "numMACoeff", false, 0, kMaxArOrder, 0);
  const int num_mod = shape.num_mod;
  out.arma = shape.num_ma > 0;
  ReadRange(r, set, bank);
  out.has_range = bank.max_speed_mps > 0 && bank.max_force_N > 0;
  shape.speeds_mmps = r.Values(set, "speedList", true);
  shape.forces = r.Values(set, "forceList", true);
  if (static_cast<int>(shape.speeds_mmps.size()) != num_mod ||
      static_cast<int>(shape.forces.size()) != num_mod)
    r.Error(set, "speedList/forceList",
            fmt::format("expected {} entries each (numMod), found {} and {}", num_mod,
                        shape.speeds_mmps.size(), shape.forces.size()));
  ReadTriangles(r, set, num_mod, bank);
  for (const auto& model : set.children("model")) {
    int idx = -1;
    auto cell = ReadModel(r, model, shape, out, idx);
    if (!cell) continue;
    if (idx >= 0 && static_cast<std::size_t>(idx) != bank.cells.size())
      r.Error(model, "modNum", "models must appear in modNum order 1, 2, ...");
    bank.cells.push_back(std::move(*cell));
  }
  if (static_cast<int>(bank.cells.size()) != num_mod)
    r.Error(set, "model",
            fmt::format("numMod says {} models, found {}", num_mod, bank.cells.size()));
  if (static_cast<int>(bank.cells.size()) == num_mod) CheckTriangles(r, set, bank, num_mod);
  diag.ThrowIfAny();
  // The toolkit renders down to 0.05 mm/s; below it it interpolates at speed ~0, where its
  // files hold var = 0 boundary models: silent, as the renderer is below min_speed_mps.
  bank.min_speed_mps = kPennMinSpeed_mps;
  // A force below 0.05 N it interpolates at 1e-4 N, next to its silent force-0 models.
  bank.light_force_N = kPennLightForce_N;
  // The geometry is flat: the vibration carries the whole texture, so no hybrid split.
  m.hybrid_cutoff_hz = 0;
  ValidateMaterial(m);
  return out;
}

}  // namespace hapticlab::renderer
