#include "hapticlab/renderer/neural.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/vibration.hpp"

namespace hapticlab::renderer {

// The runaway detector's averaging time [s] (NeuralSynth::Step).
constexpr double kRunawayWindow_s = 0.25;
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
  // scaled condition (v', f'), the last two inputs (kNeuralLinearTerms; 6-term files: quadratic).
  if (!n.linear.empty()) {
    const std::size_t M =
        unified ? static_cast<std::size_t>(n.layers.front()) - 2 : n.linear.size();
    const double* w = n.linear.data();
    double phi[kNeuralLinearTerms] = {1, 0, 0, 0, 0, 0, 0, 0, 0};
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

// Γ_U's per-cell AR part at synthesis: the AR bank's own interpolation (LSFs mixed with the
// grid's bilinear weights, ar.hpp / vibration.hpp) over the band's cells, recomputed only when
// the condition changes. Allocation-free after construction.
struct NeuralSynth::CellArMix {
  VibrationInterpolator interp;
  ArFilter filter;
  double speed_mps = std::numeric_limits<double>::quiet_NaN();  // condition of `filter`
  double force_N = std::numeric_limits<double>::quiet_NaN();

  // sum c_i x_i over the filter's order (at most the band's history, which `x` holds).
  double Predict(double v, double f, const double* x) noexcept {
    if (!(v == speed_mps && f == force_N)) {
      interp.Interpolate(v, f, true, &filter);
      speed_mps = v;
      force_N = f;
    }
    double y = 0;
    for (std::size_t i = 0; i < static_cast<std::size_t>(filter.order); ++i)
      y += filter.c[i] * x[i];
    return y;
  }
};

std::size_t NeuralNet::ParamCount() const {
  std::size_t n = 0;
  for (std::size_t l = 0; l + 1 < layers.size(); ++l)
    n += static_cast<std::size_t>(layers[l + 1]) * static_cast<std::size_t>(layers[l] + 1);
  return n;
}

// Clamped to [-1, 1]: outside the training grid the model plays its edge (as the AR bank and
// Γ_D's bilinear weights do) instead of extrapolating the condition basis and the networks.
double NeuralModel::NormSpeed(double v) const {
  const double lo = speeds_mps.front(), hi = speeds_mps.back();
  return hi > lo ? std::clamp(2 * (v - lo) / (hi - lo) - 1, -1.0, 1.0) : 0;
}
double NeuralModel::NormForce(double f) const {
  const double lo = forces_N.front(), hi = forces_N.back();
  return hi > lo ? std::clamp(2 * (f - lo) / (hi - lo) - 1, -1.0, 1.0) : 0;
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

// ---------------------------------------------------------------------------------------------
NeuralSynth::NeuralSynth(std::shared_ptr<const NeuralModel> model, std::uint64_t seed)
    : m_(std::move(model)), noise_(seed) {
  ValidateNeuralModel(*m_);
  std::size_t widest = 1;
  for (const auto& b : m_->bands) {
    BandState s;
    // 2M history (newest-first window at [head, head + M)) and, last, the band's short-term
    // mean square (the runaway detector below; kept here so Reset clears it with the history).
    s.hist.assign(2 * static_cast<std::size_t>(b.history) + 1, 0.0);
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
    if (!b.cell_ar.empty()) {  // the AR bank of the band's cells, interpolated as LPC's
      VibrationBank bank;
      bank.sample_rate_hz = rate;
      bank.grid_speeds_mps = m_->speeds_mps;
      bank.grid_forces_N = m_->forces_N;
      bank.min_speed_mps = 0;  // Step applies the model's minimum speed
      const std::size_t nf = m_->forces_N.size();
      for (std::size_t c = 0; c < b.cell_ar.size(); ++c) {
        ArCell cell;
        cell.speed_mps = m_->speeds_mps[c / nf];
        cell.force_N = m_->forces_N[c % nf];
        cell.coeffs = b.cell_ar[c];
        cell.lsf = b.cell_lsf.empty() ? ArToLsf(cell.coeffs) : b.cell_lsf[c];
        bank.cells.push_back(std::move(cell));
      }
      s.ar = std::make_unique<CellArMix>();
      s.ar->interp = VibrationInterpolator(bank);
    }
    bands_.push_back(std::move(s));
  }
  act_a_.assign(widest, 0.0);
  act_b_.assign(widest, 0.0);
}

NeuralSynth::~NeuralSynth() = default;
NeuralSynth::NeuralSynth(NeuralSynth&&) noexcept = default;
NeuralSynth& NeuralSynth::operator=(NeuralSynth&&) noexcept = default;

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
  const NeuralBand& b = m_->bands[band];
  const bool unified = m_->topology == NeuralTopology::kUnified;
  double y = Forward(b.nets[unified ? 0 : cell], unified, input, act_a_.data(), act_b_.data());
  if (unified && !b.cell_ar.empty())
    for (std::size_t i = 0; i < b.cell_ar[cell].size(); ++i) y += b.cell_ar[cell][i] * input[i];
  return y;
}

double NeuralSynth::Step(double speed_mps, double force_N, bool active) noexcept {
  const NeuralModel& m = *m_;
  if (runaway_) return 0;  // muted
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
      if (s.ar) y += s.ar->Predict(speed_mps, force_N, s.input.data());
      for (int k = 0; k < nw; ++k) {
        const auto c = static_cast<std::size_t>(cell[k]);
        if (!unified)
          y += w[k] * Forward(band.nets[c], false, s.input.data(), act_a_.data(), act_b_.data());
        sig += w[k] * band.sigma[c];
      }
      y += sig * noise_.Normal();
      // Runaway (issue #33): a non-finite sample, or a band whose RMS over about 0.25 s exceeds
      // half the declared maximum level (the clamp): an unstable filter sits at the clamp, a
      // stable model that touches it now and then (a lightly damped resonance) does not.
      const double alpha = 1 / (kRunawayWindow_s * m.sample_rate_hz / band.decimation);
      double& ms = s.hist.back();
      if (std::isfinite(y)) ms += alpha * (std::min(y * y, kNeuralMaxLevel * kNeuralMaxLevel) - ms);
      if (!std::isfinite(y) || ms > 0.25 * kNeuralMaxLevel * kNeuralMaxLevel) {
        runaway_ = true;  // mute (the caller faults)
        Reset();
        return 0;
      }
      y = std::clamp(y, -kNeuralMaxLevel, kNeuralMaxLevel);  // feedback inside the trained range
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
