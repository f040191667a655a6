#pragma once
/// @file Workbench model files (docs/workbench.md): renderer material TOML with a
/// `[workbench]` table.

#include <string>

#include "hapticlab/modeling/workbench_model.hpp"

namespace hapticlab::modeling::wb {

/// Model files: a material TOML (renderer-loadable) with `effects = [...]` and a `[workbench]`
/// table holding every effect's parameters; renderer materials without it are read from their
/// [contact] and [friction] tables.
Model LoadModel(const std::string& path);
/// Writes the model as a material TOML. With `r` and vibration fitted, an AR bank over the
/// grid of speed x force is derived from the band spectra (see docs/workbench.md).
void SaveModel(const Model& m, const std::string& path, const Replay* r = nullptr);

}  // namespace hapticlab::modeling::wb
