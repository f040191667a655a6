#pragma once
/// @file Importer for the Penn Haptic Texture Toolkit's XML model sets (Culbertson,
/// Lopez Delgado, Kuchenbecker 2014), so labs can play those published models. The toolkit's
/// files are not redistributable: HapticLab reads them from the user's own copy.
///
/// Schema read (per texture): `material`, `SampleRate` [Hz], `mu`, `numMod`, `maxSpeed`
/// [mm/s], `maxForce` [N], `speedList` [mm/s], `forceList` [N], `tri` (1-based model
/// indices), `numARCoeff`, optional `numMACoeff`; per `model`: `ARcoeff`
/// (A(z) = [1, a_1..a_p]), `ARlsf` [rad], optional `MAcoeff` ([1, b_1..b_q]) and `MAlsf`,
/// `var`, optional `gain`, `speedMod`, `forceMod`.
///
/// Rendered as the toolkit renders it (its AccSynthHashMatrix and demo code): every model is
/// driven by N(0, var) noise (ARMA: a[k] = sum c_i a[k-i] + gain (e[k] + sum b_j e[k-j])),
/// so var = 0 boundary models are silent; speed above maxSpeed and force above maxForce
/// saturate 0.01 mm/s and 0.01 N inside; synthesis runs down to 0.05 mm/s.

#include <string>

#include "hapticlab/renderer/material.hpp"

namespace hapticlab::renderer {

/// The toolkit's lowest rendered speed, 0.05 mm/s: an imported bank's min_speed_mps.
inline constexpr double kPennMinSpeed_mps = 5e-5;
/// Below this load the toolkit interpolates at kLightForceAs_N (1e-4 N): an imported bank's
/// light_force_N.
inline constexpr double kPennLightForce_N = 0.05;

struct PennImport {
  MaterialModel model;     ///< mu -> friction.mu_k; the bank; contact left at defaults;
                           ///< flat geometry and hybrid_cutoff_hz = 0 (no split)
  bool arma = false;       ///< the file holds ARMA models (the 1 kHz variant)
  bool has_range = false;  ///< the file gave maxSpeed and maxForce (imported as the bank's range)
  /// Largest |c_i| difference between the file's AR coefficients and those rebuilt from the
  /// file's LSFs (a check of the file and of our LSF convention; ~1e-5 from 6-digit LSFs).
  double max_lsf_reconstruction_error = 0;
};

/// Reads one `Models_<name>.xml`. Speeds are converted from mm/s to m/s.
/// @throws hapticlab::InputError naming the file, the element and what was expected.
PennImport ImportPennXml(const std::string& path);

}  // namespace hapticlab::renderer
