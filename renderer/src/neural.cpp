#include "hapticlab/renderer/neural.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/core/toml_util.hpp"

namespace hapticlab::renderer {
namespace {

// Bilinear weights on the grid (clamped at the edges): up to four cells, speed-major index.
int GridWeights(const std::vector<double>& vs, const std::vector<double>& fs, double v, double f,
                int* cell, double* w) {
  auto axis = [](const std::vector<double>& g, double x, int* i0, double* t) {
    if (g.size() < 2 || x <= g.front()) {
      *i0 = 0;
      *t = 0;
      return;
    }
    if (x >= g.back()) {
      *i0 = static_cast<int>(g.size()) - 2;
      *t = 1;
      return;
    }
    int i = 0;
    while (x > g[static_cast<std::size_t>(i) + 1]) ++i;
    *i0 = i;
    *t = (x - g[static_cast<std::size_t>(i)]) /
         (g[static_cast<std::size_t>(i) + 1] - g[static_cast<std::size_t>(i)]);
  };
  int iv, jf;
  double tv, tf;
  axis(vs, v, &iv, &tv);
  axis(fs, f, &jf, &tf);
  const int nf = static_cast<int>(fs.size());
  const int n1 = vs.size() > 1 ? 2 : 1, n2 = fs.size() > 1 ? 2 : 1;
  int k = 0;
  for (int a = 0; a < n1; ++a)
    for (int b = 0; b < n2; ++b) {
      const double wt = (n1 > 1 ? (a ? tv : 1 - tv) : 1.0) * (n2 > 1 ? (b ? tf : 1 - tf) : 1.0);
      if (wt <= 0) continue;
      cell[k] = (iv + a) * nf + (jf + b);
      w[k++] = wt;
    }
  return k;
}

// Γ_U's condition basis of the linear part: the biquadratic tensor basis (1, v', v'^2) x
// (1, f', f'^2), 9 terms; files from before 2026-11-23 have its first 6 terms (quadratic).
constexpr std::size_t kLinearTerms = 9, kLinearTermsQuadratic = 6;

// One second-order section of a Butterworth low- or high-pass (bilinear transform with
// pre-warping; `q` the section's quality factor). Two sections with q = 0.5412 and 1.3066
// make the fourth-order filter (hand-written: BiquadCoeffs has only the q = 0.7071 section).
BiquadCoeffs ButterworthSection(double fc, double fs, double q, bool high) {
  const double k = std::tan(std::numbers::pi * fc / fs);
  const double norm = 1.0 / (1.0 + k / q + k * k);
  BiquadCoeffs c;
  c.b0 = high ? norm : k * k * norm;
  c.b1 = high ? -2.0 * norm : 2.0 * k * k * norm;
  c.b2 = c.b0;
  c.a1 = 2.0 * (k * k - 1.0) * norm;
  c.a2 = (1.0 - k / q + k * k) * norm;
  return c;
}

// Allocation-free forward pass; `a` and `b` hold at least the widest layer.
double Forward(const NeuralNet& n, bool unified, const double* in, double* a, double* b) {
  const double* x = in;
  double* dst = a;
  std::size_t off = 0;
  const std::size_t L = n.layers.size() - 1;
  for (std::size_t l = 0; l < L; ++l) {
    const int ni = n.layers[l], no = n.layers[l + 1];
    const Eigen::Map<const Eigen::MatrixXd> W(n.params.data() + off, no, ni);
    const Eigen::Map<const Eigen::VectorXd> bias(
        n.params.data() + off + static_cast<std::size_t>(no * ni), no);
    const Eigen::Map<const Eigen::VectorXd> xin(x, ni);
    Eigen::Map<Eigen::VectorXd> out(dst, no);
    out.noalias() = W * xin;
    out += bias;
    // tanh(x) = 1 - 2 / (exp(2x) + 1): Eigen vectorizes exp for doubles but not tanh, and
    // tanh dominated the cost. Exact to rounding; saturates correctly at +-inf.
    if (l + 1 < L) out = (1.0 - 2.0 / ((2.0 * out.array()).exp() + 1.0)).matrix();
    off += static_cast<std::size_t>(no) * static_cast<std::size_t>(ni + 1);
    x = dst;
    dst = dst == a ? b : a;
  }
  double y = x[0];
  // The linear part over the M history inputs; Γ_U's coefficients are biquadratic in the
  // scaled condition (v', f'), the last two inputs (kLinearTerms; 6-term files: quadratic).
  if (!n.linear.empty()) {
    const std::size_t M =
        unified ? static_cast<std::size_t>(n.layers.front()) - 2 : n.linear.size();
    const double* w = n.linear.data();
    double phi[kLinearTerms] = {1, 0, 0, 0, 0, 0, 0, 0, 0};
    std::size_t terms = 1;
    if (unified) {
      const double v = in[M], f = in[M + 1];
      phi[1] = v, phi[2] = f, phi[3] = v * v, phi[4] = v * f, phi[5] = f * f;
      phi[6] = v * v * f, phi[7] = v * f * f, phi[8] = v * v * f * f;
      terms = n.linear.size() / M;
    }
    for (std::size_t t = 0; t < terms; ++t) {
      double acc = 0;
      for (std::size_t i = 0; i < M; ++i) acc += w[t * M + i] * in[i];
      y += phi[t] * acc;
    }
  }
  return y;
}

}  // namespace

std::size_t NeuralNet::ParamCount() const {
  std::size_t n = 0;
  for (std::size_t l = 0; l + 1 < layers.size(); ++l)
    n += static_cast<std::size_t>(layers[l + 1]) * static_cast<std::size_t>(layers[l] + 1);
  return n;
}

double NeuralModel::NormSpeed(double v) const {
  const double lo = speeds_mps.front(), hi = speeds_mps.back();
  return hi > lo ? 2 * (v - lo) / (hi - lo) - 1 : 0;
}
double NeuralModel::NormForce(double f) const {
  const double lo = forces_N.front(), hi = forces_N.back();
  return hi > lo ? 2 * (f - lo) / (hi - lo) - 1 : 0;
}

std::vector<NeuralBand> DefaultNeuralBands() {
  std::vector<NeuralBand> b(4);
  const double lo[] = {20, 100, 200, 500}, hi[] = {100, 200, 500, 1000};
  const int g[] = {8, 4, 1, 1};
  for (int i = 0; i < 4; ++i) {
    b[static_cast<std::size_t>(i)].lo_hz = lo[i];
    b[static_cast<std::size_t>(i)].hi_hz = hi[i];
    b[static_cast<std::size_t>(i)].decimation = g[i];
    b[static_cast<std::size_t>(i)].history = 50;
  }
  return b;
}

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
      const std::size_t want_lin = H * (uni ? kLinearTerms : 1);
      if (!n.linear.empty() && n.linear.size() != want_lin &&
          !(uni && n.linear.size() == H * kLinearTermsQuadratic))
        return fmt::format(
            "{}: {} linear weights, expected 0 or {}{}", where, n.linear.size(), want_lin,
            uni ? fmt::format(" (or {}: the quadratic basis)", H * kLinearTermsQuadratic) : "");
      for (const double p : n.linear)
        if (!std::isfinite(p)) return where + ": non-finite linear weight";
    }
    if (!(band.scale > 0)) return where + ": scale must be positive";
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
  s += fmt::format("topology = \"{}\"\nsample_rate_hz = {:.17g}\nmin_speed_mps = {:.17g}\n",
                   m.topology == NeuralTopology::kUnified ? "unified" : "decomposed",
                   m.sample_rate_hz, m.min_speed_mps);
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
  }
  WriteTextFile(path, s);
}

NeuralModel LoadNeuralModel(const std::string& path) {
  const toml::table doc = ParseTomlFile(path);
  Diagnostics d;
  auto line = [](const toml::node* n) { return n ? static_cast<int>(n->source().begin.line) : 0; };
  auto numbers = [&](const toml::node* n, const std::string& key, std::vector<double>* out) {
    const auto* a = n ? n->as_array() : nullptr;
    if (!a) {
      d.Add(path, line(n), key, "expected an array of numbers");
      return;
    }
    for (const auto& x : *a) {
      const auto v = x.value<double>();
      if (!v) {
        d.Add(path, line(&x), key, "expected numbers");
        return;
      }
      out->push_back(*v);
    }
  };
  NeuralModel m;
  const auto topo = doc["topology"].value<std::string>();
  if (topo == "unified")
    m.topology = NeuralTopology::kUnified;
  else if (topo == "decomposed")
    m.topology = NeuralTopology::kDecomposed;
  else
    d.Add(path, line(doc.get("topology")), "topology", "expected \"unified\" or \"decomposed\"");
  m.sample_rate_hz = doc["sample_rate_hz"].value_or(0.0);
  m.min_speed_mps = doc["min_speed_mps"].value_or(0.01);
  numbers(doc.get("speeds_mps"), "speeds_mps", &m.speeds_mps);
  numbers(doc.get("forces_N"), "forces_N", &m.forces_N);
  const auto* bands = doc["band"].as_array();
  if (!bands) d.Add(path, 0, "band", "expected [[band]] tables");
  for (std::size_t i = 0; bands && i < bands->size(); ++i) {
    const auto* t = bands->get(i)->as_table();
    const std::string k = fmt::format("band[{}]", i + 1);
    if (!t) {
      d.Add(path, line(bands->get(i)), k, "expected a table");
      continue;
    }
    NeuralBand b;
    b.lo_hz = (*t)["lo_hz"].value_or(0.0);
    b.hi_hz = (*t)["hi_hz"].value_or(0.0);
    b.decimation = static_cast<int>((*t)["decimation"].value_or(int64_t{0}));
    b.history = static_cast<int>((*t)["history"].value_or(int64_t{0}));
    b.scale = (*t)["scale"].value_or(0.0);
    std::vector<double> layers;
    numbers(t->get("layers"), k + ".layers", &layers);
    numbers(t->get("sigma"), k + ".sigma", &b.sigma);
    const auto* nets = (*t)["nets"].as_array();
    if (!nets) d.Add(path, line(t), k + ".nets", "expected an array of parameter arrays");
    for (std::size_t j = 0; nets && j < nets->size(); ++j) {
      NeuralNet n;
      for (const double x : layers) n.layers.push_back(static_cast<int>(x));
      numbers(nets->get(j), fmt::format("{}.nets[{}]", k, j + 1), &n.params);
      b.nets.push_back(std::move(n));
    }
    if (const auto* lin = (*t)["linear"].as_array()) {
      if (lin->size() != b.nets.size())
        d.Add(path, line(t->get("linear")), k + ".linear",
              fmt::format("expected one array per network ({})", b.nets.size()));
      for (std::size_t j = 0; j < lin->size() && j < b.nets.size(); ++j)
        numbers(lin->get(j), fmt::format("{}.linear[{}]", k, j + 1), &b.nets[j].linear);
    }
    m.bands.push_back(std::move(b));
  }
  d.ThrowIfAny();
  if (const std::string problem = NeuralModelProblem(m); !problem.empty())
    throw InputError(path, 0, "band", problem);
  return m;
}

// ---------------------------------------------------------------------------------------------
NeuralSynth::NeuralSynth(std::shared_ptr<const NeuralModel> model, std::uint64_t seed)
    : m_(std::move(model)), noise_(seed) {
  ValidateNeuralModel(*m_);
  std::size_t widest = 1;
  for (const auto& b : m_->bands) {
    BandState s;
    s.hist.assign(2 * static_cast<std::size_t>(b.history), 0.0);
    s.input.assign(static_cast<std::size_t>(b.nets.front().layers.front()), 0.0);
    const double rate = m_->sample_rate_hz / b.decimation;
    if (&b == &m_->bands.front())
      s.hp.SetCoeffs(BiquadCoeffs::ButterworthHighPass(0.5 * b.lo_hz, rate));
    s.up = PolyphaseUpsampler(b.decimation, kTaps);
    // The crossovers (docs/modeling-neural.md): fourth-order Butterworth pairs at every band
    // boundary below the Nyquist frequency; band b takes the high-pass of every boundary below
    // it and the low-pass of its own top, so the powers sum to one at every frequency.
    const double nyq = 0.5 * m_->sample_rate_hz;
    for (const auto& lower : m_->bands) {
      if (&lower == &b) break;
      if (lower.hi_hz < nyq)
        for (const double q : kButterworth4Q)
          s.xover[static_cast<std::size_t>(s.nxover++)] =
              Biquad(ButterworthSection(lower.hi_hz, m_->sample_rate_hz, q, true));
    }
    if (b.hi_hz < nyq)
      for (const double q : kButterworth4Q)
        s.xover[static_cast<std::size_t>(s.nxover++)] =
            Biquad(ButterworthSection(b.hi_hz, m_->sample_rate_hz, q, false));
    for (const auto& n : b.nets)
      for (const int w : n.layers) widest = std::max(widest, static_cast<std::size_t>(w));
    bands_.push_back(std::move(s));
  }
  act_a_.assign(widest, 0.0);
  act_b_.assign(widest, 0.0);
}

void NeuralSynth::Reset() noexcept {
  for (auto& s : bands_) {
    std::fill(s.hist.begin(), s.hist.end(), 0.0);
    s.head = s.phase = 0;
    s.hp.Reset();
    s.up.Reset();
    for (auto& x : s.xover) x.Reset();
  }
  running_ = false;
}

double NeuralSynth::Evaluate(std::size_t band, std::size_t cell, const double* input) noexcept {
  return Forward(m_->bands[band].nets[cell], m_->topology == NeuralTopology::kUnified, input,
                 act_a_.data(), act_b_.data());
}

double NeuralSynth::Step(double speed_mps, double force_N, bool active) noexcept {
  const NeuralModel& m = *m_;
  if (!active || !(speed_mps >= m.min_speed_mps) || !std::isfinite(force_N)) {
    if (running_) Reset();
    return 0;
  }
  running_ = true;
  int cell[4];
  double w[4];
  const int nw = GridWeights(m.speeds_mps, m.forces_N, speed_mps, force_N, cell, w);
  const bool unified = m.topology == NeuralTopology::kUnified;
  double sum = 0;
  for (std::size_t b = 0; b < bands_.size(); ++b) {
    const NeuralBand& band = m.bands[b];
    BandState& s = bands_[b];
    const auto M = static_cast<std::size_t>(band.history);
    if (s.phase == 0) {
      std::copy(s.hist.begin() + s.head, s.hist.begin() + s.head + static_cast<std::ptrdiff_t>(M),
                s.input.begin());
      if (unified) {
        s.input[M] = m.NormSpeed(speed_mps);
        s.input[M + 1] = m.NormForce(force_N);
      }
      double y = 0, sig = 0;
      if (unified) y = Forward(band.nets[0], true, s.input.data(), act_a_.data(), act_b_.data());
      for (int k = 0; k < nw; ++k) {
        const auto c = static_cast<std::size_t>(cell[k]);
        if (!unified)
          y += w[k] * Forward(band.nets[c], false, s.input.data(), act_a_.data(), act_b_.data());
        sig += w[k] * band.sigma[c];
      }
      y += sig * noise_.Normal();
      if (!std::isfinite(y)) y = 0;
      y = std::clamp(y, -10.0, 10.0);  // keep the feedback inside the trained range
      s.head = s.head == 0 ? static_cast<int>(M) - 1 : s.head - 1;
      s.hist[static_cast<std::size_t>(s.head)] = s.hist[static_cast<std::size_t>(s.head) + M] = y;
      s.up.Push(s.hp.Step(y));
    }
    double out = s.up.Output(s.phase);
    for (int k = 0; k < s.nxover; ++k) out = s.xover[static_cast<std::size_t>(k)].Step(out);
    s.phase = (s.phase + 1) % band.decimation;
    sum += band.scale * out;
  }
  return std::isfinite(sum) ? sum : 0.0;
}

}  // namespace hapticlab::renderer
