#pragma once
// Ground truth of a real sample (internal to sim): analytic geometry and the contact
// vibration level and resonance.

#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/sim/sim_lab.hpp"

namespace hapticlab::sim::internal {

inline constexpr double kPi = std::numbers::pi;

inline std::uint64_t HashId(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  return h;
}

// One sinusoidal component A sin(kx x + ky y + phi).
struct Wave {
  double a, kx, ky, phi;
};

// Analytic truth geometry of a profile: macro (isotropic + directional, patch-modulated)
// and micro components. Height above the layer's mean [m] and its gradient.
class TruthGeometry {
 public:
  explicit TruthGeometry(const MaterialProfile& p) {
    Rng rng(HashId(p.id));
    const double k0 = 2 * kPi / p.wavelength_m;
    const double iso_w = (1 - p.anisotropy) * p.roughness_m / std::sqrt(6 / 2.0);
    for (int j = 0; j < 6; ++j) {
      const double k = k0 * rng.Uniform(0.7, 1.4), th = rng.Uniform(0, kPi);
      macro_.push_back({iso_w, k * std::cos(th), k * std::sin(th), rng.Uniform(0, 2 * kPi)});
    }
    const double dir = rng.Uniform(0, kPi);
    macro_.push_back({p.anisotropy * p.roughness_m * std::sqrt(2.0), k0 * std::cos(dir),
                      k0 * std::sin(dir), rng.Uniform(0, 2 * kPi)});
    beta_ = p.inhomogeneity;
    kp_ = k0 / 10;
    pp_ = rng.Uniform(0, 2 * kPi);
    // Micro-roughness at 0.25-0.5 mm: what a stylus tip still follows and a photometric
    // map at the texture's resolution smooths away; it drives 100-600 Hz vibration at
    // stroking speeds.
    for (int j = 0; j < 4; ++j) {
      const double k = 2 * kPi / rng.Uniform(0.25e-3, 0.5e-3), th = rng.Uniform(0, kPi);
      micro_.push_back({p.micro_roughness_m / std::sqrt(2.0), k * std::cos(th), k * std::sin(th),
                        rng.Uniform(0, 2 * kPi)});
    }
    bound_ = 0;
    for (const auto& w : macro_) bound_ += std::abs(w.a);
    bound_ *= 1 + beta_;
    for (const auto& w : micro_) bound_ += std::abs(w.a);
  }
  // Macro height (what a photometric map resolves), with gradient.
  void Macro(double x, double y, double* h, double* hx, double* hy) const {
    double g = 0, gx = 0, gy = 0;
    for (const auto& w : macro_) {
      const double ph = w.kx * x + w.ky * y + w.phi;
      g += w.a * std::sin(ph);
      gx += w.a * w.kx * std::cos(ph);
      gy += w.a * w.ky * std::cos(ph);
    }
    const double m = 1 + beta_ * std::sin(kp_ * x + pp_) * std::sin(kp_ * y + 2 * pp_);
    const double mx = beta_ * kp_ * std::cos(kp_ * x + pp_) * std::sin(kp_ * y + 2 * pp_);
    const double my = beta_ * kp_ * std::sin(kp_ * x + pp_) * std::cos(kp_ * y + 2 * pp_);
    *h = g * m;
    *hx = gx * m + g * mx;
    *hy = gy * m + g * my;
  }
  // Full height with micro-roughness, its gradient, and the second derivative along (ux, uy)
  // of the micro part (the stylus acceleration it imposes at speed 1 m/s).
  void Full(double x, double y, double ux, double uy, double* h, double* hx, double* hy,
            double* micro_dd) const {
    Macro(x, y, h, hx, hy);
    double dd = 0;
    for (const auto& w : micro_) {
      const double ph = w.kx * x + w.ky * y + w.phi;
      *h += w.a * std::sin(ph);
      *hx += w.a * w.kx * std::cos(ph);
      *hy += w.a * w.ky * std::cos(ph);
      const double ku = w.kx * ux + w.ky * uy;
      dd -= w.a * ku * ku * std::sin(ph);
    }
    *micro_dd = dd;
  }
  double bound() const { return bound_; }

 private:
  std::vector<Wave> macro_, micro_;
  double beta_ = 0, kp_ = 1, pp_ = 0, bound_ = 0;
};

// Contact vibration level of the truth at (speed, load) [m/s^2 RMS].
inline double VibrationRms(const MaterialProfile& p, double v, double f) {
  return p.vibration_rms_mps2 * std::pow(std::max(v, 0.0) / 0.08, 0.8) *
         std::pow(std::max(f, 0.0) / 1.2, 0.5);
}

// AR(2) resonator at f0 with quality Q at rate fs: c1, c2 and the stationary variance of its
// output for unit-variance innovations.
inline void Resonator(double f0, double q, double fs, double* c1, double* c2, double* var) {
  const double w = 2 * kPi * f0 / fs, r = std::exp(-kPi * f0 / (q * fs));
  *c1 = 2 * r * std::cos(w);
  *c2 = -r * r;
  *var = (1 - *c2) / ((1 + *c2) * ((1 - *c2) * (1 - *c2) - *c1 * *c1));
}

}  // namespace hapticlab::sim::internal
