#pragma once
// The mutator the fuzz tests share: deterministic edits of a seed input (bit flips, random
// bytes, format tokens, numbers at the edges of ranges, erased and duplicated ranges, long runs
// of one token), so the same seed gives the same inputs on every run.

#include <random>
#include <string>
#include <vector>

namespace hapticlab::fuzz {

/// Format tokens and edge-of-range numbers spliced into inputs.
extern const std::vector<std::string> kDictionary;

/// One to four edits of `in`, drawn from `rng`.
std::string Mutate(const std::string& in, std::mt19937_64& rng);

}  // namespace hapticlab::fuzz
