// The neural vibration model's file (TOML, format_version 1 or 2) and its consistency checks:
// NeuralModelProblem / ValidateNeuralModel, SaveNeuralModel, LoadNeuralModel and the per-cell
// LSFs the synthesis mixes (FillNeuralCellLsf). The synthesis itself is neural.cpp.
#include <fmt/format.h>
#include <toml++/toml.h>

#include <cmath>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/neural.hpp"

namespace hapticlab::renderer {
namespace {
// Γ_U's per-cell AR part (NeuralBand::cell_ar): "" when absent or consistent.
std::string CellArProblem(const NeuralModel& m, const NeuralBand& band) {
  if (band.cell_ar.empty()) {
    if (!band.cell_lsf.empty()) return "cell_lsf without cell_ar";
    return "";
  }
  if (m.topology != NeuralTopology::kUnified)
    return "cell_ar is the unified (Γ_U) model's linear part; this model is decomposed";
  const std::size_t cells = m.speeds_mps.size() * m.forces_N.size();
  const auto M = static_cast<std::size_t>(band.history);
  if (band.cell_ar.size() != cells)
    return fmt::format("{} cell_ar filters, expected {} (one per grid cell)", band.cell_ar.size(),
                       cells);
  if (!band.nets.front().linear.empty())
    return "both cell_ar and the network's linear weights: expected one linear part";
  if (M > static_cast<std::size_t>(kMaxArOrder))
    return fmt::format("cell_ar needs history <= {} (the AR interpolation's largest order)",
                       kMaxArOrder);
  const std::size_t nf = m.forces_N.size();
  for (std::size_t c = 0; c < cells; ++c) {
    const auto& a = band.cell_ar[c];
    const std::string cell = fmt::format("cell_ar[{}] ({:g} m/s, {:g} N)", c + 1,
                                         m.speeds_mps[c / nf], m.forces_N[c % nf]);
    if (a.empty() || a.size() > M || a.size() != band.cell_ar.front().size())
      return fmt::format(
          "{}: {} coefficients, expected 1 to {} (the band's history), the same in every cell",
          cell, a.size(), M);
    for (const double x : a)
      if (!std::isfinite(x)) return cell + ": non-finite coefficient";
    if (!IsStableAr(a))
      return cell + ": not minimum phase (its LSFs, which the interpolation mixes, do not exist)";
  }
  if (!band.cell_lsf.empty()) {
    if (band.cell_lsf.size() != cells) return "cell_lsf does not match cell_ar";
    for (std::size_t c = 0; c < cells; ++c)
      if (band.cell_lsf[c].size() != band.cell_ar[c].size())
        return "cell_lsf does not match cell_ar";
  }
  return "";
}

}  // namespace

std::string NeuralModelProblem(const NeuralModel& m) {
  if (m.speeds_mps.empty() || m.forces_N.empty()) return "neural model: empty speed or force grid";
  for (const auto* g : {&m.speeds_mps, &m.forces_N})
    for (std::size_t i = 1; i < g->size(); ++i)
      if (!((*g)[i] > (*g)[i - 1])) return "neural model: grid values must be strictly ascending";
  if (!(m.sample_rate_hz > 0)) return "neural model: sample_rate_hz must be positive";
  if (m.bands.empty() || m.bands.size() > kMaxNeuralBands)
    return fmt::format("neural model: {} bands, expected 1 to {}", m.bands.size(), kMaxNeuralBands);
  const std::size_t cells = m.speeds_mps.size() * m.forces_N.size();
  for (std::size_t b = 0; b < m.bands.size(); ++b) {
    const auto& band = m.bands[b];
    if (!(band.lo_hz >= 0 && band.hi_hz > band.lo_hz) ||
        (b > 0 && std::abs(band.lo_hz - m.bands[b - 1].hi_hz) > 1e-9))
      return fmt::format(
          "neural model band {}: bands must be ascending and contiguous (lo_hz = hi_hz of the band "
          "below)",
          b + 1);
    const std::string where =
        fmt::format("neural model band {} ({:g}-{:g} Hz)", b + 1, band.lo_hz, band.hi_hz);
    if (band.decimation < 1 || band.history < 1)
      return where + ": decimation and history must be >= 1";
    if (band.hi_hz > 0.5 * m.sample_rate_hz / band.decimation + 1e-9)
      return where + ": the band's upper edge exceeds the Nyquist frequency of its decimated rate";
    const std::size_t want = m.topology == NeuralTopology::kUnified ? 1 : cells;
    if (band.nets.size() != want)
      return fmt::format("{}: {} networks, expected {}", where, band.nets.size(), want);
    if (band.sigma.size() != cells)
      return fmt::format("{}: {} sigma values, expected {}", where, band.sigma.size(), cells);
    const int inputs = band.history + (m.topology == NeuralTopology::kUnified ? 2 : 0);
    for (const auto& n : band.nets) {
      if (n.layers.size() < 2 || n.layers.front() != inputs || n.layers.back() != 1)
        return fmt::format("{}: layers must run from {} inputs to 1 output", where, inputs);
      if (n.params.size() != n.ParamCount())
        return fmt::format("{}: {} parameters, the layers need {}", where, n.params.size(),
                           n.ParamCount());
      for (const double p : n.params)
        if (!std::isfinite(p)) return where + ": non-finite weight";
      const auto H = static_cast<std::size_t>(band.history);
      const bool uni = m.topology == NeuralTopology::kUnified;
      const std::size_t want_lin = H * (uni ? kNeuralLinearTerms : 1);
      if (!n.linear.empty() && n.linear.size() != want_lin &&
          !(uni && n.linear.size() == H * kNeuralLinearTermsQuadratic))
        return fmt::format(
            "{}: {} linear weights, expected 0 or {}{}", where, n.linear.size(), want_lin,
            uni ? fmt::format(" (or {}: the quadratic basis)", H * kNeuralLinearTermsQuadratic)
                : "");
      for (const double p : n.linear)
        if (!std::isfinite(p)) return where + ": non-finite linear weight";
    }
    if (!(band.scale > 0)) return where + ": scale must be positive";
    if (const std::string p = CellArProblem(m, band); !p.empty()) return where + ": " + p;
  }
  return "";
}

void ValidateNeuralModel(const NeuralModel& m) {
  const std::string problem = NeuralModelProblem(m);
  HL_REQUIRE(problem.empty(), problem);
}

// ---------------------------------------------------------------------------------------------
void SaveNeuralModel(const NeuralModel& m, const std::string& path) {
  ValidateNeuralModel(m);
  auto list = [](const auto& v) {
    std::string s = "[";
    for (std::size_t i = 0; i < v.size(); ++i)
      s += fmt::format("{}{:.17g}", i ? ", " : "", static_cast<double>(v[i]));
    return s + "]";
  };
  std::string s =
      "# HapticLab neural texture model (dissertation ch. III.3; docs/modeling-neural.md)\n";
  s += fmt::format("format_version = {}\n", kNeuralFormatVersion);
  s += fmt::format("topology = \"{}\"\nsample_rate_hz = {:.17g}\nmin_speed_mps = {:.17g}\n",
                   m.topology == NeuralTopology::kUnified ? "unified" : "decomposed",
                   m.sample_rate_hz, m.min_speed_mps);
  s += fmt::format("calibration = \"{}\"\n", m.calibrated ? "calibrated" : "uncalibrated");
  s += "speeds_mps = " + list(m.speeds_mps) + "\nforces_N = " + list(m.forces_N) + "\n";
  for (const auto& b : m.bands) {
    s += fmt::format(
        "\n[[band]]\nlo_hz = {:.17g}\nhi_hz = {:.17g}\ndecimation = {}\nhistory = {}\nscale = "
        "{:.17g}\n",
        b.lo_hz, b.hi_hz, b.decimation, b.history, b.scale);
    s += "layers = " + list(b.nets.front().layers) + "\nsigma = " + list(b.sigma) + "\nnets = [\n";
    for (const auto& n : b.nets) s += "  " + list(n.params) + ",\n";
    s += "]\n";
    if (!b.nets.front().linear.empty()) {
      s += "linear = [\n";
      for (const auto& n : b.nets) s += "  " + list(n.linear) + ",\n";
      s += "]\n";
    }
    if (!b.cell_ar.empty()) {  // one AR filter per grid cell, speed-major (as sigma)
      s += "cell_ar = [\n";
      for (const auto& a : b.cell_ar) s += "  " + list(a) + ",\n";
      s += "]\n";
    }
  }
  WriteTextFile(path, s);
}

namespace {

// A neural model file being read: its problems collected with file, line and key.
struct NeuralReader {
  const std::string& path;
  Diagnostics& d;

  static int Line(const toml::node* n) { return n ? static_cast<int>(n->source().begin.line) : 0; }
  void Numbers(const toml::node* n, const std::string& key, std::vector<double>* out) const {
    const auto* a = n ? n->as_array() : nullptr;
    if (!a) {
      d.Add(path, Line(n), key, "expected an array of numbers");
      return;
    }
    for (const auto& x : *a) {
      const auto v = x.value<double>();
      if (!v) {
        d.Add(path, Line(&x), key, "expected numbers");
        return;
      }
      out->push_back(*v);
    }
  }

  // The file's top-level keys (format_version, topology, rates, calibration, grid) into m;
  // returns the format version (1 when absent: before Γ_U's per-cell AR part).
  std::int64_t Header(const toml::table& doc, NeuralModel* m) const {
    const auto version = doc["format_version"].value<int64_t>().value_or(1);
    if (doc.contains("format_version") && !doc["format_version"].value<int64_t>())
      d.Add(path, Line(doc.get("format_version")), "format_version", "expected an integer");
    else if (version < 1 || version > kNeuralFormatVersion)
      throw InputError(path, Line(doc.get("format_version")), "format_version",
                       fmt::format("version {}; this build reads versions 1 to {} (written by a "
                                   "newer HapticLab?)",
                                   version, kNeuralFormatVersion));
    const auto topo = doc["topology"].value<std::string>();
    if (topo == "unified")
      m->topology = NeuralTopology::kUnified;
    else if (topo == "decomposed")
      m->topology = NeuralTopology::kDecomposed;
    else
      d.Add(path, Line(doc.get("topology")), "topology", "expected \"unified\" or \"decomposed\"");
    m->sample_rate_hz = doc["sample_rate_hz"].value_or(0.0);
    m->min_speed_mps = doc["min_speed_mps"].value_or(0.01);
    if (const auto* c = doc.get("calibration")) {
      const auto word = c->value<std::string>();
      if (word != "calibrated" && word != "uncalibrated")
        d.Add(path, Line(c), "calibration", "expected \"calibrated\" or \"uncalibrated\"");
      m->calibrated = word != "uncalibrated";
    }
    Numbers(doc.get("speeds_mps"), "speeds_mps", &m->speeds_mps);
    Numbers(doc.get("forces_N"), "forces_N", &m->forces_N);
    return version;
  }

  // One [[band]] table (k: "band[i]"): its nets, linear parts and per-cell AR filters.
  NeuralBand Band(const toml::table& t, const std::string& k, std::int64_t version) const {
    NeuralBand b;
    b.lo_hz = t["lo_hz"].value_or(0.0);
    b.hi_hz = t["hi_hz"].value_or(0.0);
    b.decimation = static_cast<int>(t["decimation"].value_or(int64_t{0}));
    b.history = static_cast<int>(t["history"].value_or(int64_t{0}));
    b.scale = t["scale"].value_or(0.0);
    std::vector<double> layers;
    Numbers(t.get("layers"), k + ".layers", &layers);
    Numbers(t.get("sigma"), k + ".sigma", &b.sigma);
    const auto* nets = t["nets"].as_array();
    if (!nets) d.Add(path, Line(&t), k + ".nets", "expected an array of parameter arrays");
    for (std::size_t j = 0; nets && j < nets->size(); ++j) {
      NeuralNet n;
      for (const double x : layers) n.layers.push_back(static_cast<int>(x));
      Numbers(nets->get(j), fmt::format("{}.nets[{}]", k, j + 1), &n.params);
      b.nets.push_back(std::move(n));
    }
    if (const auto* lin = t["linear"].as_array()) {
      if (lin->size() != b.nets.size())
        d.Add(path, Line(t.get("linear")), k + ".linear",
              fmt::format("expected one array per network ({})", b.nets.size()));
      for (std::size_t j = 0; j < lin->size() && j < b.nets.size(); ++j)
        Numbers(lin->get(j), fmt::format("{}.linear[{}]", k, j + 1), &b.nets[j].linear);
    }
    if (const auto* car = t.get("cell_ar")) {
      const auto* a = car->as_array();
      if (version < 2)
        d.Add(path, Line(car), k + ".cell_ar", "needs format_version = 2 (absent: version 1)");
      else if (!a)
        d.Add(path, Line(car), k + ".cell_ar", "expected an array of coefficient arrays");
      for (std::size_t j = 0; version >= 2 && a && j < a->size(); ++j) {
        b.cell_ar.emplace_back();
        Numbers(a->get(j), fmt::format("{}.cell_ar[{}]", k, j + 1), &b.cell_ar.back());
      }
    }
    return b;
  }
};

}  // namespace

NeuralModel LoadNeuralModel(const std::string& path) {
  const toml::table doc = ParseTomlFile(path);
  Diagnostics d;
  const NeuralReader read{path, d};
  NeuralModel m;
  const std::int64_t version = read.Header(doc, &m);
  const auto* bands = doc["band"].as_array();
  if (!bands) d.Add(path, 0, "band", "expected [[band]] tables");
  for (std::size_t i = 0; bands && i < bands->size(); ++i) {
    const auto* t = bands->get(i)->as_table();
    const std::string k = fmt::format("band[{}]", i + 1);
    if (!t) {
      d.Add(path, NeuralReader::Line(bands->get(i)), k, "expected a table");
      continue;
    }
    m.bands.push_back(read.Band(*t, k, version));
  }
  d.ThrowIfAny();
  if (const std::string problem = NeuralModelProblem(m); !problem.empty())
    throw InputError(path, 0, "band", problem);
  FillNeuralCellLsf(&m);
  return m;
}

void FillNeuralCellLsf(NeuralModel* m) {
  for (auto& b : m->bands) {
    b.cell_lsf.clear();
    for (const auto& a : b.cell_ar) b.cell_lsf.push_back(ArToLsf(a));
  }
}

}  // namespace hapticlab::renderer
