#pragma once
// The neural models' training data (modeling/src/neural_data.cpp), for FitNeural
// (modeling/src/neural.cpp) and its tests: the recordings' speed x force grid, the ideal band
// split the networks train on, and the validation score that selects between the trained
// networks and the linear parts alone. Internal to the modeling library.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "hapticlab/modeling/neural.hpp"
#include "hapticlab/modeling/vibration.hpp"
#include "hapticlab/renderer/neural.hpp"

namespace hapticlab::modeling::neural_internal {

/// Equal within 1e-6 relative (grid values read from files).
bool Near(double a, double b);
/// The distinct values of `v` (Near), ascending.
std::vector<double> Unique(std::vector<double> v);
/// The index of `x` in grid `g` (Near), or -1.
int Index(const std::vector<double>& g, double x);

/// Ideal (FFT) band-pass of `x` sampled at `fs` to [lo, hi) [Hz]: the bands of a recording sum
/// exactly to it, and each is limited to [lo, hi) so that decimation by γ with
/// hi <= rate / (2 γ) does not alias (a Butterworth band-pass's skirts would fold back).
std::vector<double> BandSplit(const std::vector<double>& x, double fs, double lo, double hi);

/// The per-cell AR order of Γ_U's per-cell fallback (max_condition_basis_radius): chosen as the LPC
/// bank chooses its order (the criterion summed over the band's training signals, one order for all
/// cells: LSF interpolation needs equal orders), at most M and preprocess.max_order (or
/// preprocess.order when fixed).
int PerCellArOrder(const std::vector<std::vector<double>>& train, int M,
                   const VibrationFitOptions& preprocess);

/// Welch segment of the validation E_s [samples].
constexpr std::size_t kValidationSegment = 256;

/// Mean free-running E_s (eq. 3.1, the Fig. 3.7 measure) of model `m` with `bands` against the
/// last `validation_fraction` of every preprocessed recording `pre[i]` (recording `recs[i]`'s
/// condition), each synthesized with seed `seed + i`; recordings whose validation part is
/// shorter than two segments are skipped (0 when none is left).
double ValidationEs(const renderer::NeuralModel& m, const std::vector<renderer::NeuralBand>& bands,
                    const std::vector<Recording>& recs, const std::vector<std::vector<double>>& pre,
                    double validation_fraction, std::uint64_t seed);

/// Γ_U's condition basis (renderer/neural.hpp): its 9 terms, the first `terms` of them at the
/// scaled (v', f') (neural_stability.cpp).
inline constexpr std::size_t kConditionTerms = 9;
Eigen::VectorXd ConditionBasis(double v, double f, Eigen::Index terms = kConditionTerms);
/// The terms a speeds x forces grid determines (issue #33: no more terms than nodes): degrees
/// in v' up to min(speeds - 1, 2) and in f' up to min(forces - 1, 2): 2 x 2 bilinear (4), 3 x 2
/// six, 3 x 3 and larger the biquadratic 9. The others are fitted as zero.
std::array<bool, kConditionTerms> ActiveConditionTerms(std::size_t speeds, std::size_t forces);
/// The largest pole radius of A(z) = 1 - sum c_i z^-i (bisection on the radius with the
/// step-down stability test; 0 for no coefficients).
double MaxPoleRadius(std::span<const double> c);
/// The largest pole radius of the AR filter W phi(v', f') (W: M x terms, the network's linear
/// weights) over an n x n grid of the scaled hull [-1, 1]^2; speed_mps and force_N hold the
/// scaled v', f' where it is.
NeuralPoleRadius ConditionBasisMaxRadius(const Eigen::MatrixXd& W, int n = 41);
/// Refuses (InputError naming the band, its largest pole radius and where) a model whose
/// linear part is not stable over the hull in every band (NeuralMaxPoleRadius); `note` gets
/// each band's radius.
void RequireStableLinearParts(const renderer::NeuralModel& m,
                              const std::function<void(const std::string&)>& note);

}  // namespace hapticlab::modeling::neural_internal
