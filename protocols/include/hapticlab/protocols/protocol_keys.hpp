#pragma once
/// @file The protocol file's key tables, for docs/formats.md.

#include <string>

namespace hapticlab::protocols {

/// The key tables of the protocol file (every table's keys with type, range, unit, default
/// and meaning) in Markdown, as docs/formats.md shows them; printed from the declared field
/// tables the parser reads through (core/fields.hpp), so the document cannot drift from it.
std::string ProtocolKeyTables();

}  // namespace hapticlab::protocols
