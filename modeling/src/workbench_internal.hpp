#pragma once
// Internal to the workbench sources: the resolved form of a model (each effect with its
// parameter values in ParamSpec order) and the replay kernels prediction and fitting share.

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "hapticlab/modeling/workbench_fit.hpp"

namespace hapticlab::modeling::wb::internal {

inline constexpr double kMm = 1e-3;

/// The core every model has: the contact stiffness (one parameter, K1mm_N).
const Effect& CoreEffect();

// An effect with its parameter values in the order of its ParamSpec list.
struct Resolved {
  const Effect* e;
  std::string name;
  std::vector<ParamSpec> specs;
  std::vector<double> p;
};

/// The model's effects of channel c (the core first for the normal channel), values from the
/// model or the specs' initial values.
std::vector<Resolved> Resolve(const Model& m, const Replay& r, Channel c);
/// Writes the resolved values back into the model.
void Store(Model* m, const std::vector<Resolved>& res);
/// Normal force of one sample [N] (0 out of contact).
double NormalForce(const std::vector<Resolved>& eff, const Replay::Sample& s);
/// Friction force the surface exerts on the tool [N], sample frame, over every sample.
void FrictionForces(const std::vector<Resolved>& eff, const Replay& r, double* ftx, double* fty);
/// Vibration design row: intercept, then every vibration effect's features.
std::vector<double> VibrationRow(const std::vector<Resolved>& eff, const Replay::Window& w);
/// Whether a block belongs to the split (even blocks train, odd are held out).
bool InSplit(int block, Split s);
/// E_s of one window (eq. 3.1 over band magnitudes): measured and predicted band powers.
inline double WindowEs(const std::vector<double>& measured, const std::vector<double>& predicted) {
  double num = 0, den = 0;
  for (std::size_t b = 0; b < predicted.size() && b < measured.size(); ++b) {
    const double a = std::sqrt(measured[b]), q = std::sqrt(predicted[b]);
    num += (a - q) * (a - q);
    den += a * a;
  }
  return den > 0 ? std::sqrt(num / den) : 0;
}

/// Robust SD of white noise on a smooth signal from its second differences over three samples:
/// they have variance 6 sigma^2, and their median absolute value is 0.6745 of their SD (the
/// median ignores the signal's own curvature, reversals and contact edges). 0 for none.
inline double NoiseSdFromSecondDifferences(std::vector<double> d2) {
  if (d2.empty()) return 0;
  for (auto& x : d2) x = std::abs(x);
  const auto mid = d2.begin() + static_cast<std::ptrdiff_t>(d2.size() / 2);
  std::nth_element(d2.begin(), mid, d2.end());
  return *mid / 0.674489750196 / std::sqrt(6.0);
}

/// The FFT bins (1 .. n/2-1) of each of r's bands for a window of n samples at `rate`: those
/// inside the band, else the one nearest its centre (as PrepareReplay picks them).
std::vector<std::vector<int>> BandBins(const Replay& r, int n, double rate);

}  // namespace hapticlab::modeling::wb::internal
