#pragma once
/// @file Workbench model files (docs/workbench.md): renderer material TOML with a
/// `[workbench]` table.

#include <string>
#include <vector>

#include "hapticlab/modeling/workbench_model.hpp"

namespace hapticlab::renderer {
struct MaterialModel;
}

namespace hapticlab::modeling::wb {

/// Model files: a material TOML (renderer-loadable) with `effects = [...]` and a `[workbench]`
/// table holding every effect's parameters; renderer materials without it are read from their
/// [contact] and [friction] tables.
Model LoadModel(const std::string& path);
/// Writes the model as a material TOML. With `r` and vibration fitted, an AR bank over the
/// grid of speed x force is derived from the band spectra (see docs/workbench.md). The file is
/// read back with LoadModel before it replaces `path`: a model that would not read back throws
/// PreconditionError (no file is left); a file that cannot be written throws
/// std::runtime_error (both exit 1 in the command line, not 2: neither is the user's input).
void SaveModel(const Model& m, const std::string& path, const Replay* r = nullptr);
/// The effects a renderer material's [contact] and [friction] parameters say were fitted (for
/// a material without an effect list): coulomb and dahl; viscous when mu_b > 0, hc-damping
/// when B > 0, hc-exponent when n != 1.
std::vector<std::string> ContactEffectsOf(const renderer::MaterialModel& mm);

}  // namespace hapticlab::modeling::wb
