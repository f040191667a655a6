#pragma once
/// @file A protocol's identity: its parsed content in one canonical text, independent of
/// comments, whitespace, key order, quoting style and number spelling (2 and 2.0 are one
/// value). Two protocol files are the same protocol exactly when their canonical forms are
/// equal; the study database stores a hash of it (runner/protocol_identity.hpp) and refuses a
/// protocol whose form differs, naming every key that changed (CanonicalDifferences).
///
/// The form is the TOML document as JSON: object keys sorted (byte order), no whitespace,
/// arrays in file order (the order of materials, methods and phases matters), strings with
/// JSON escapes, integers as integers, a float whose value is a whole number below 2^53 as
/// that integer, other floats in their shortest round-trip spelling, dates and times as
/// strings. What the file leaves out is left out: writing a default value explicitly (e.g.
/// `repetitions = 1`) changes the form, as it changes the text a reader sees.

#include <string>
#include <vector>

#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::protocols {

/// The canonical form of a protocol's text (Protocol::text, the file as read).
/// @throws InputError naming p.file when the text is not valid TOML
std::string CanonicalForm(const Protocol& p);
/// The canonical form of a protocol text; `file` names it in errors.
/// @throws InputError naming `file` when the text is not valid TOML
std::string CanonicalFormOfText(const std::string& toml_text, const std::string& file);

/// One semantic difference between two protocol texts.
struct ProtocolChange {
  std::string key;               ///< e.g. "phase[2].repetitions", "material[3]"
  std::string old_value;         ///< canonical JSON of the old value; "(absent)" when added
  std::string new_value;         ///< canonical JSON of the new value; "(absent)" when removed
  std::string Describe() const;  ///< "phase[2].repetitions: 3 -> 4"
};

/// Every key whose value differs between two protocol texts, in key order (tables by key,
/// arrays element by element). Empty exactly when the canonical forms are equal.
/// @throws InputError when a text is not valid TOML
std::vector<ProtocolChange> CanonicalDifferences(const std::string& old_text,
                                                 const std::string& new_text);

}  // namespace hapticlab::protocols
