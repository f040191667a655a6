#pragma once
/// @file The ground truth's friction law, shared by every simulator of real surfaces: the
/// simulated rig's truth samples (sim/src/sim_device.cpp) and the workbench's synthetic
/// measurements (modeling/src/workbench_sim.cpp). Header-only, depending on nothing but the
/// standard library (CMake target `hapticlab::sim_truth`), so `modeling` can use it without
/// linking the simulated rig (docs/architecture.md).
///
/// Friction coefficient with a Gaussian Stribeck rise at low speed:
///   mu(v) = mu_k + dmu_s exp(-(v / v_s)^2)
/// mu_k the kinetic coefficient, dmu_s the static excess (mu_s - mu_k, >= 0), v_s the Stribeck
/// speed [m/s], v the tangential sliding speed [m/s] (>= 0). A profile that states the static
/// coefficient as a ratio mu_s / mu_k maps exactly to dmu_s = mu_k (ratio - 1).

#include <cmath>

namespace hapticlab::sim_truth {

struct StribeckFriction {
  double mu_k = 0;                   ///< kinetic coefficient (dimensionless, >= 0)
  double dmu_s = 0;                  ///< static excess mu_s - mu_k (dimensionless, >= 0)
  double stribeck_speed_mps = 1e-3;  ///< v_s [m/s], > 0

  /// The law for a static-to-kinetic ratio mu_s / mu_k (>= 1).
  static constexpr StribeckFriction FromRatio(double mu_k, double ratio,
                                              double speed_mps) noexcept {
    return {mu_k, mu_k * (ratio - 1), speed_mps};
  }
  /// Coefficient at sliding speed v [m/s] (dimensionless). Allocation-free, real-time safe.
  double Mu(double speed_mps) const noexcept {
    const double u = speed_mps / stribeck_speed_mps;
    return mu_k + dmu_s * std::exp(-u * u);
  }
};

}  // namespace hapticlab::sim_truth
