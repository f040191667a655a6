#pragma once
/// @file Importer for the Penn Haptic Texture Toolkit's XML model sets (Culbertson,
/// Lopez Delgado, Kuchenbecker 2014), so labs can play those published models. The toolkit's
/// files are not redistributable: HapticLab reads them from the user's own copy.
///
/// Schema read (per texture): `material`, `SampleRate` [Hz], `mu`, `numMod`, `speedList`
/// [mm/s], `forceList` [N], `tri` (1-based model indices), `numARCoeff`, optional
/// `numMACoeff`; per `model`: `ARcoeff` (A(z) = [1, a_1..a_p]), `ARlsf` [rad], optional
/// `MAcoeff` ([1, b_1..b_q]) and `MAlsf`, `var`, optional `gain`, `speedMod`, `forceMod`.

#include <string>

#include "hapticlab/renderer/material.hpp"

namespace hapticlab::renderer {

struct PennImport {
  MaterialModel model;          ///< mu -> friction.mu_k; the bank; contact left at defaults
  bool arma = false;            ///< the file holds ARMA models (the 1 kHz variant)
  /// Largest |c_i| difference between the file's AR coefficients and those rebuilt from the
  /// file's LSFs (a check of the file and of our LSF convention; ~1e-5 from 6-digit LSFs).
  double max_lsf_reconstruction_error = 0;
};

/// Reads one `Models_<name>.xml`. Speeds are converted from mm/s to m/s.
/// @throws hapticlab::InputError naming the file, the element and what was expected.
PennImport ImportPennXml(const std::string& path);

}  // namespace hapticlab::renderer
