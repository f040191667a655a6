#pragma once
/// @file The ch. III.4 cross-validation loop shared by every vibration model kind (LPC bank,
/// Γ_U, Γ_D): fit on the recordings at the training speeds x forces, synthesize every
/// recording's condition, and score it with E_s against the preprocessed recording (the
/// Fig. 3.7 table). The model kinds differ only in how they fit and synthesize.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "hapticlab/modeling/vibration.hpp"

namespace hapticlab::modeling {

/// A fitted model's synthesis at one recording's (speed [m/s], force [N]) condition: `n`
/// samples at the model rate, seeded, after the model has settled.
using ConditionSynthesizer = std::function<std::vector<double>(const Recording& condition,
                                                               std::size_t n, std::uint64_t seed)>;

/// Fits a model on the training recordings and returns its synthesizer.
using CvFit = std::function<ConditionSynthesizer(const std::vector<Recording>& training)>;

/// True when x equals an element of `set` within 1e-6 relative (conditions read from files).
bool NearAny(const std::vector<double>& set, double x);

/// The loop: recordings at train_speeds_mps x train_forces_N are the training set (at least
/// 3), every recording is synthesized (seed + its index) and scored; rows in recording order,
/// means over training and held-out rows. `preprocess` gives the measured signal the
/// synthesized one is compared with (as the fit preprocesses it).
/// @throws InputError ("<command line>", field "training conditions") with fewer than 3
/// training recordings.
CvResult CrossValidateModel(const std::vector<Recording>& recordings,
                            const std::vector<double>& train_speeds_mps,
                            const std::vector<double>& train_forces_N,
                            const VibrationFitOptions& preprocess, const CvFit& fit,
                            std::uint64_t seed);

}  // namespace hapticlab::modeling
