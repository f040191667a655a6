#pragma once
/// @file Training the neural texture model (dissertation ch. III.3): frequency-decomposed MLPs,
/// unified (Γ_U) or decomposed (Γ_D), from the same recordings and preprocessing as the LPC
/// bank, and the ch. III.4 cross-validation on the same E_s table (Fig. 3.7). Synthesis is in
/// renderer/neural.hpp.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hapticlab/modeling/mlp.hpp"
#include "hapticlab/modeling/vibration.hpp"
#include "hapticlab/renderer/neural.hpp"

namespace hapticlab::modeling {

struct NeuralFitOptions {
  renderer::NeuralTopology topology = renderer::NeuralTopology::kUnified;
  std::vector<renderer::NeuralBand> bands = renderer::DefaultNeuralBands();  ///< layout only
  std::vector<int> hidden_large = {30, 25, 15, 5};  ///< Γ_U (every band) and Γ_D band 1 (thesis)
  std::vector<int> hidden_small = {30, 15, 5};      ///< Γ_D bands 2-4 (thesis)
  MlpTrainOptions train{.max_epochs = 40, .batch = 64, .learning_rate = 2e-3, .patience = 6};
  VibrationFitOptions preprocess;  ///< resampling to the model rate and band limit (as LPC)
  double min_speed_mps = 0.01;
  /// SD of noise added to the training histories (units of the band's RMS). An exactly
  /// band-limited signal is almost perfectly predictable from 50 past samples, and a
  /// predictor trained on clean histories free-runs into a limit cycle; trained on noisy
  /// histories it stays a noise-driven process with the band's spectrum. 0.3 was chosen on
  /// the synthetic textures of tests/modeling/neural_test.cpp (NeuralFig37 runs with it).
  double input_noise = 0.3;
  /// SD of white noise added to each band's training signal before the pairs are cut (units
  /// of the band's RMS): histories and targets alike. Default 0: the training signals cover
  /// their whole decimated range and need no conditioning; a dither puts a white floor
  /// into every band (docs/modeling-neural.md).
  double signal_noise = 0.0;
  /// Give every network a linear autoregressive part fitted by least squares on the clean
  /// histories (Γ_U: see unified_linear); the MLP learns what it leaves.
  bool linear_part = true;
  /// Γ_U's linear part: AR coefficients biquadratic in the scaled (v', f') (NeuralNet::linear;
  /// no more terms than the grid has nodes), kept when its filter's largest pole radius over a
  /// 41 x 41 grid of the hull is below this. Otherwise that band falls back to one AR fit per
  /// training cell (order as the LPC bank chooses it) mixed in LSF form with the grid's bilinear
  /// weights, as the LPC bank mixes its fits (NeuralBand::cell_ar, file format 2): stable by
  /// construction. Below 1 asks for a stability margin; 0 always takes the per-cell form.
  double max_condition_basis_radius = 1.0;
  /// Ridge of the linear part's least squares, relative to the mean diagonal of its normal
  /// matrix (keeps the coefficients, and their condition dependence, small where the data
  /// do not determine them).
  double linear_ridge = 1e-6;
  /// Keep the networks' nonlinear part only when it earns its place on validation data:
  /// every network's output layer starts at zero (the model starts as its linear part), and
  /// after training the model with the trained networks and the model of the linear parts
  /// alone (each with its own calibrated sigma) both synthesize every recording's condition;
  /// the one with the lower mean E_s against the recordings' validation parts (their last
  /// train.validation_fraction, which no linear part was fitted on) is returned. The one-step
  /// validation MSE is not the criterion: the networks lower it (by 12 % in the full-rate
  /// bands of the nonlinear AR grid) and still raise the free-running E_s
  /// (docs/modeling-neural.md). false: always keep the networks. Needs linear_part.
  bool validate_nonlinear_part = true;
  /// When validation keeps the linear parts alone, refit them on every row of every recording
  /// (training and validation parts; the LPC bank fits its AR models on whole recordings)
  /// and recalibrate sigma for them: select on the validation split, then refit the chosen
  /// model on all data. The networks, when kept, are returned as trained beside the linear
  /// parts of the training rows (an MLP learns what its linear part leaves; refitting the
  /// linear part under it would change that). Needs validate_nonlinear_part.
  bool refit_linear_part = true;
  int threads = 0;  ///< networks trained in parallel; 0: all cores
  /// Progress (what, networks done, total), from worker threads: every 5th training epoch of
  /// each network ("band 2: epoch 10/40, validation MSE 0.41") and when a network finishes.
  std::function<void(const std::string&, int, int)> progress;
};

/// Trains the model on recordings at the conditions of a full speed x force grid (the
/// thesis's design). Band b's network runs on the preprocessed recording low-passed (ideal,
/// FFT) to the Nyquist frequency of its decimated rate and decimated by γ_b, in units of its
/// RMS over all recordings; the band itself is selected at synthesis by the crossovers
/// (renderer/neural.hpp). Each network learns y[m] from y[m-1..m-M] (Γ_U: and v, f scaled to
/// [-1, 1]); the last 20 % of every recording is the early-stopping validation set. Sigma
/// per band and cell: the one-step residual RMS, calibrated so that free-running synthesis
/// has the recording's power inside the band. The networks' nonlinear part is then kept or
/// dropped on validation data (validate_nonlinear_part). Seeded by options.train.seed.
/// @throws InputError when the recordings do not form a full grid (listing what is missing).
renderer::NeuralModel FitNeural(const std::vector<Recording>& recordings,
                                const NeuralFitOptions& o);

/// Ch. III.4 cross-validation for the neural model: fit on the recordings at the training
/// speeds x forces, synthesize every recording's condition with renderer::NeuralSynth
/// (seeded), E_s against the preprocessed recording. Same rows as CrossValidate.
CvResult CrossValidateNeural(const std::vector<Recording>& recordings,
                             const std::vector<double>& train_speeds_mps,
                             const std::vector<double>& train_forces_N, const NeuralFitOptions& o,
                             std::uint64_t seed = 1);

/// Where a band's linear part comes closest to instability.
struct NeuralPoleRadius {
  double radius = 0;                  ///< the largest pole radius of the linear AR filter
  double speed_mps = 0, force_N = 0;  ///< where on the grid it is
};
/// The largest pole radius of band `band`'s linear part over an n x n grid spanning the
/// training grid's rectangle (the hull of its conditions; the synthesizer clamps a condition
/// outside it to its edge), the filter formed as renderer::NeuralSynth forms it: Γ_U's
/// condition basis W phi(v', f'), or its per-cell AR fits mixed in LSF form; Γ_D's cells'
/// linear weights mixed with the bilinear weights. Radius 0: no linear part. FitNeural refuses a
/// model whose radius is not below 1 in every band.
NeuralPoleRadius NeuralMaxPoleRadius(const renderer::NeuralModel& m, std::size_t band, int n = 41);

/// Synthesizes `n` samples at the model rate for a condition (after `settle` samples).
std::vector<double> SynthesizeNeural(const renderer::NeuralModel& m, double speed_mps,
                                     double force_N, std::size_t n, std::uint64_t seed,
                                     std::size_t settle = 4000);

}  // namespace hapticlab::modeling
