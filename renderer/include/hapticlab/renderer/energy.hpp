#pragma once
/// @file Stability check (dissertation ch. V.1.2, Fig. 5.3): the work the rendered force
/// field does on the tool around a closed path. A passive (conservative or dissipative)
/// field returns <= 0; a positive result is energy the surface creates.

#include <string>

#include "hapticlab/renderer/force.hpp"

namespace hapticlab::renderer {

/// The closed path, in the x-z plane at y = 0, traversed in `steps` equal pieces per side.
struct EnergyPath {
  /// Path A (for `norm`): on h(x) = A sin(2 pi x / l) with z measured from the mean surface:
  /// (0, 0) -> (l/4, 0) -> (l/4, A) -> (0, A) -> (0, 0). Path B (friction algorithms):
  /// from the surface top at x = 0, down dz_max, along +x by dx_max, up dz_max, back.
  enum class Kind { kA, kB } kind = Kind::kA;
  double dx_max_m = 1e-4;   ///< path B's tangential excursion [m]
  double dz_max_m = 1e-4;   ///< path B's penetration [m]
  int steps = 20000;        ///< integration steps per side
  double speed_mps = 0.01;  ///< tool speed along the path (for damping and Dahl) [m/s]
};

struct EnergyResult {
  double energy_J = 0;             ///< numeric work done by the surface on the tool [J]
  double normal_energy_J = 0;      ///< part done by the force's z component [J]
  double tangential_energy_J = 0;  ///< part done by its x component (friction, tilted normal) [J]
  bool has_closed_form = false;
  /// Path A with `norm`: eq. (5.2). Path B with a friction algorithm: the normal part's
  /// K (T(dx) - T(0)) dz (linear texture contact, B = 0), which the friction part adds to.
  double closed_form_J = 0;
  double bound_J = 0;  ///< eq. (5.3)'s order of magnitude K mu_k^2 dx dz (path B) [J]
  /// Path B: K max|h'| dx dz + K mu_k^2 dx dz, a bound on the gain of the friction
  /// algorithms (normal part over a sloped texture plus the friction part) [J].
  double gain_bound_J = 0;
};

/// Integrates the work of `algorithm`'s force around `path` on a sine texture of amplitude
/// A and wavelength l, with the material's contact and friction parameters (its geometry is
/// replaced by the sine). Midpoint rule, the force model stepped along the path.
EnergyResult ComputeEnergy(const MaterialModel& material, ForceAlgorithm algorithm,
                           double amplitude_m, double wavelength_m, const EnergyPath& path);

/// Eq. (5.2): Delta E = K A^2 / 2 + K l^2 / (4 pi^2) (1 - sqrt(l^2 + 4 A^2 pi^2) / l).
double ClosedFormEnergyNorm(double stiffness_N_per_m, double amplitude_m, double wavelength_m);

}  // namespace hapticlab::renderer
