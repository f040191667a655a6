#pragma once
/// @file Spelling participant codes that fit a protocol's `[study] participant_code` pattern
/// (`hapticlab participant new`, the simulated participants of `study power`): a prefix and a
/// zero-padded number, e.g. P01 for the default pattern, NU001 for "^NU[0-9]{3}$".

#include <set>
#include <string>

#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::protocols {

struct CodeFormat {
  std::string prefix;  ///< letters before the number, e.g. "NU"
  int digits = 2;      ///< the number's width, zero-padded
};

/// The format of p's codes. The prefix is `prefix` when given, else the pattern's literal
/// start (the characters after '^' up to the first that is not a letter, digit, '-' or '_',
/// less a last one that a quantifier makes optional or repeated), else "P". The width is the
/// smallest of 2..6, then 1, at which prefix + 1 or prefix + 10^(width-1) matches the pattern.
/// Patterns are regular expressions: no general inverse exists, so a pattern whose codes do
/// not start with a fixed prefix needs one given (`--prefix`).
/// @throws InputError naming p.file and study.participant_code (or `prefix_option` when a
///         prefix was given) when no width fits
CodeFormat InferCodeFormat(const Protocol& p, const std::string& prefix = "",
                           const std::string& prefix_option = "--prefix");

/// prefix + n zero-padded to the format's width.
std::string FormatCode(const CodeFormat& f, long n);

/// The lowest-numbered code of the format that matches p's pattern and is not in `taken`.
/// @throws InputError when every number of the width is taken or refused by the pattern
std::string NextFreeCode(const Protocol& p, const CodeFormat& f,
                         const std::set<std::string>& taken);

}  // namespace hapticlab::protocols
