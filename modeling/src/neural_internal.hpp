#pragma once
// The neural models' training data (modeling/src/neural_data.cpp), for FitNeural
// (modeling/src/neural.cpp) and its tests: the recordings' speed x force grid, the ideal band
// split the networks train on, and the validation score that selects between the trained
// networks and the linear parts alone. Internal to the modeling library.

#include <cstdint>
#include <vector>

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

/// Welch segment of the validation E_s [samples].
constexpr std::size_t kValidationSegment = 256;

/// Mean free-running E_s (eq. 3.1, the Fig. 3.7 measure) of model `m` with `bands` against the
/// last `validation_fraction` of every preprocessed recording `pre[i]` (recording `recs[i]`'s
/// condition), each synthesized with seed `seed + i`; recordings whose validation part is
/// shorter than two segments are skipped (0 when none is left).
double ValidationEs(const renderer::NeuralModel& m, const std::vector<renderer::NeuralBand>& bands,
                    const std::vector<Recording>& recs, const std::vector<std::vector<double>>& pre,
                    double validation_fraction, std::uint64_t seed);

}  // namespace hapticlab::modeling::neural_internal
