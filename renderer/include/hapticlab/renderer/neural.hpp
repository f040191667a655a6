#pragma once
/// @file Neural texture vibration (dissertation ch. III.3, Fig. 3.3): frequency-decomposed
/// MLP predictors of the next acceleration sample from decimated history, unified (Γ_U: one
/// network per band with speed and load as two extra inputs) or decomposed (Γ_D: one network
/// per band and per (speed, force) cell of a grid, outputs interpolated bilinearly between
/// the four neighbours, ch. III.3.5).
///
/// Free-running synthesis. A predictor fed its own output converges to a fixed point or a
/// limit cycle; a texture's vibration is a random process. Each band therefore runs as a
/// nonlinear autoregression driven by noise: y[m] = NN(y[m-1..m-M], v, f) + sigma e[m],
/// e ~ N(0, 1), with sigma the network's one-step residual standard deviation on its training
/// data (per cell, interpolated like the outputs). This is the nonlinear counterpart of the
/// LPC model's excitation; sigma is then calibrated so that free-running synthesis at each
/// training cell has the recording's power inside the band. Each band's network runs on a
/// signal that covers its whole decimated range (not only the band: a band-limited signal is
/// an ill-conditioned prediction problem); the output path selects the band: the lowest band
/// is high-passed at half its lower edge (drift), every band is upsampled by γ with a
/// windowed-sinc polyphase interpolator (16 taps per phase) and then passes fourth-order
/// Butterworth crossovers at the model rate: the high-passes of every band boundary below it
/// and the low-pass at its own top. Butterworth low- and high-pass of one order and cut-off
/// are power-complementary (|L|^2 + |H|^2 = 1), and the bands are independent processes, so
/// their powers sum to the model's at every frequency (within 0.5 dB over 20-950 Hz with the
/// interpolators' roll-off, tests/modeling/neural_test.cpp). Latency: 8 decimated samples
/// per band (32 ms for band 1, none at γ = 1) plus the crossovers' group delay.

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/renderer/biquad.hpp"
#include "hapticlab/renderer/upsampler.hpp"

namespace hapticlab::renderer {

/// A trained MLP: tanh hidden layers, linear scalar output. Parameters per layer l: W_l
/// (out x in, column-major) then b_l (out).
struct NeuralNet {
  std::vector<int> layers;  ///< sizes from input to output (output 1)
  std::vector<double> params;
  /// Optional linear autoregressive part added to the MLP's output (empty: none). Over the
  /// M history inputs x_i: Γ_D, M weights a_i, y += sum a_i x_i; Γ_U, 9 M weights, one block
  /// of M per term of the biquadratic condition basis phi = (1, v', f', v'^2, v' f', f'^2,
  /// v'^2 f', v' f'^2, v'^2 f'^2) (v', f' the network's scaled speed and force inputs):
  /// y += sum_t phi_t sum_i w[t M + i] x_i. Files with 6 M weights (the quadratic basis, its
  /// first six terms; before 2026-11-23) still load (docs/modeling-neural.md: why).
  std::vector<double> linear;
  std::size_t ParamCount() const;
};

/// One band of Fig. 3.3.
struct NeuralBand {
  double lo_hz = 20, hi_hz = 100;  ///< the band
  int decimation = 10;             ///< γ: the band runs at sample_rate / γ
  int history = 50;                ///< M: past decimated samples fed to the network
  double scale = 1;  ///< band signal standard deviation [m/s^2]; nets work in units of it
  std::vector<NeuralNet> nets;  ///< Γ_U: one; Γ_D: one per grid cell (speed-major)
  std::vector<double> sigma;    ///< residual SD per grid cell (units of `scale`)
  /// Γ_U's linear part interpolated as the LPC bank interpolates (file format_version 2,
  /// issue #19): one AR(p) per grid cell (speed-major, as `sigma`; the same order p, 1 <= p
  /// <= M, in every cell), coefficients c_1..c_p over the newest p samples of the band's
  /// history in units of `scale` (ar.hpp's convention), each minimum phase.
  /// At synthesis the cells' LSFs are mixed with the AR bank's weights (VibrationInterpolator:
  /// bilinear on the grid, clamped at its edges) and converted back, and the network's output
  /// adds sum c_i x_i; the MLP is the correction on top. Empty: no such part (the network's
  /// own `linear`, if any, is used: files before format_version 2).
  std::vector<std::vector<double>> cell_ar;
  /// LSFs [rad/sample] of `cell_ar` (same shape), filled by the fit and on load; empty: the
  /// synthesizer computes them (ArToLsf's scan: milliseconds per cell at high order).
  std::vector<std::vector<double>> cell_lsf;
};

enum class NeuralTopology { kUnified, kDecomposed };

inline constexpr std::size_t kMaxNeuralBands = 8;
/// The neural model's declared maximum level, +-10 of a band's RMS (`scale`): the feedback is
/// clamped there, and a band whose RMS over about 0.25 s exceeds half of it (an unstable
/// filter sitting at the clamp, not a noise-driven process that touches it now and then) or
/// any non-finite sample is a runaway: NeuralSynth mutes itself (runaway()).
inline constexpr double kNeuralMaxLevel = 10;
/// Γ_U's condition basis of the linear part: the biquadratic tensor basis (1, v', v'^2) x
/// (1, f', f'^2), 9 terms; files from before 2026-11-23 have its first 6 terms (quadratic).
inline constexpr std::size_t kNeuralLinearTerms = 9, kNeuralLinearTermsQuadratic = 6;

struct NeuralModel {
  NeuralTopology topology = NeuralTopology::kUnified;
  double sample_rate_hz = 2000;              ///< model rate [Hz]
  double min_speed_mps = 0.01;               ///< off below this speed (as the AR bank)
  std::vector<double> speeds_mps, forces_N;  ///< the training grid (ascending)
  std::vector<NeuralBand> bands;
  /// false: trained on recordings in their own units (`calibration = "uncalibrated"` in the
  /// file), so sigma and the output are in those units, not m/s^2. Absent in a file: calibrated.
  bool calibrated = true;
  /// Γ_U condition inputs: v and f mapped linearly from [lo, hi] of the grid to [-1, 1],
  /// clamped there (outside the grid the model plays its edge).
  double NormSpeed(double v) const;
  double NormForce(double f) const;
};

/// The thesis's four bands with γ = 8, 4, 1, 1 at 2 kHz: each band's top at most 0.4 of its
/// decimated rate, so the interpolator passes the band whole (the text's "γ = 10 for all
/// networks" would alias bands 2-4; see docs/modeling-neural.md).
std::vector<NeuralBand> DefaultNeuralBands();

/// Checks sizes (layer chains, one net or one per cell, sigma per cell): "" when the model is
/// consistent, else the problem (loaders turn it into an InputError naming their file).
std::string NeuralModelProblem(const NeuralModel& m);
/// Precondition form of NeuralModelProblem: throws PreconditionError naming the problem.
void ValidateNeuralModel(const NeuralModel& m);

/// Fills every band's `cell_lsf` from its `cell_ar`.
/// @throws PreconditionError when a cell's AR filter is not minimum phase.
void FillNeuralCellLsf(NeuralModel* m);

/// The file format version SaveNeuralModel writes: 2 (`format_version = 2`, Γ_U's per-cell AR
/// part `cell_ar`); files without `format_version` are version 1 and still load and play.
inline constexpr int kNeuralFormatVersion = 2;

/// Reads/writes a neural model file (TOML; docs/modeling-neural.md). Versions 1 and 2 load; a
/// newer version is an InputError naming the file, the field and the versions read.
/// @throws hapticlab::InputError with file, line and key.
NeuralModel LoadNeuralModel(const std::string& path);
void SaveNeuralModel(const NeuralModel& m, const std::string& path);

/// Synthesis at the model rate. Every buffer is sized in the constructor; Step is noexcept
/// and allocation-free (the vibration loop calls it).
class NeuralSynth {
 public:
  NeuralSynth(std::shared_ptr<const NeuralModel> model, std::uint64_t seed);
  ~NeuralSynth();
  NeuralSynth(NeuralSynth&&) noexcept;
  NeuralSynth& operator=(NeuralSynth&&) noexcept;
  /// The next model-rate sample [m/s^2] at the current speed and normal force; zero (and the
  /// state cleared) when inactive or slower than the model's minimum speed. A runaway band
  /// (kNeuralMaxLevel: not finite, or its short-term RMS above half the level) mutes the
  /// synthesizer: zero from then on, runaway() true, until ClearRunaway().
  double Step(double speed_mps, double force_N, bool active) noexcept;
  void Reset() noexcept;  ///< clears the state (not the runaway latch)
  bool runaway() const noexcept { return runaway_; }
  void ClearRunaway() noexcept { runaway_ = false; }
  /// One network evaluation of band b at cell c on an input vector (for tests): Γ_D, cell
  /// c's network; Γ_U, the network plus cell c's AR part (when the model has `cell_ar`).
  double Evaluate(std::size_t band, std::size_t cell, const double* input) noexcept;

 private:
  static constexpr int kTaps = 16;  // interpolator taps per phase
  static constexpr double kButterworth4Q[2] = {0.54119610014619701, 1.3065629648763766};
  struct CellArMix;  // Γ_U's per-cell AR part: the AR bank's interpolator and its last filter
  struct BandState {
    std::vector<double> hist;   // 2M: newest-first window at [head, head + M)
    std::vector<double> input;  // M (+2) network input
    int head = 0, phase = 0;
    Biquad hp;              // lowest band only: drift high-pass at lo / 2 (decimated rate)
    PolyphaseUpsampler up;  // by γ, kTaps taps per phase
    std::array<Biquad, 2 * kMaxNeuralBands> xover{};  // crossover sections at the model rate
    int nxover = 0;
    std::unique_ptr<CellArMix> ar;  // null: the band has no cell_ar
  };
  std::shared_ptr<const NeuralModel> m_;
  std::vector<BandState> bands_;
  std::vector<double> act_a_, act_b_;  // activations
  Rng noise_;
  bool running_ = false;
  bool runaway_ = false;
};

}  // namespace hapticlab::renderer
