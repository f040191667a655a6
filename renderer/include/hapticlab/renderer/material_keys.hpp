#pragma once
/// @file The material model file's key tables, for docs/formats.md.

#include <string>

namespace hapticlab::renderer {

/// The key tables of the material model file (every table's keys with type, range, unit,
/// default and meaning) in Markdown, printed from the declared field tables ParseMaterial
/// reads through and ValidateMaterial checks against (core/fields.hpp), as docs/formats.md
/// shows them.
std::string MaterialKeyTables();

}  // namespace hapticlab::renderer
