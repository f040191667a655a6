#include "mutate.hpp"

#include <algorithm>
#include <cstdint>

namespace hapticlab::fuzz {

// Tokens the mutator splices in: syntax of the formats and numbers at the edges of ranges.
const std::vector<std::string> kDictionary = {
    "[",
    "]",
    "[[",
    "]]",
    "{",
    "}",
    "=",
    ",",
    ".",
    "\"",
    "'",
    "\"\"\"",
    "'''",
    "#",
    "\n",
    "\r\n",
    "\\",
    "\xEF\xBB\xBF",
    "<",
    ">",
    "</",
    "/>",
    "<value>",
    "</value>",
    "<tri>",
    "<model>",
    "&amp;",
    "<![CDATA[",
    "0",
    "-1",
    "1e10",
    "1e308",
    "-1e308",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "nan",
    "inf",
    "-inf",
    "0x7fffffff",
    "1e-320",
    "true",
    "false",
    "\"\"",
};

std::string Mutate(const std::string& in, std::mt19937_64& rng) {
  std::string s = in;
  auto pick = [&](std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(rng() % n); };
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits; ++e) {
    switch (rng() % 8) {
      case 0:  // flip a bit
        if (!s.empty()) s[pick(s.size())] ^= static_cast<char>(1 << (rng() % 8));
        break;
      case 1:  // a random byte
        if (!s.empty()) s[pick(s.size())] = static_cast<char>(rng() % 256);
        break;
      case 2:
      case 3:  // splice a dictionary token
        s.insert(pick(s.size() + 1), kDictionary[pick(kDictionary.size())]);
        break;
      case 4: {  // erase a range
        const auto at = pick(s.size() + 1);
        s.erase(at, std::min<std::size_t>(1 + pick(32), s.size() - at));
        break;
      }
      case 5: {  // duplicate a range
        const auto at = pick(s.size() + 1);
        const auto piece = s.substr(at, 1 + pick(64));
        s.insert(pick(s.size() + 1), piece);
        break;
      }
      case 6: {  // replace a token with an edge-of-range number
        const auto at = pick(s.size() + 1);
        const auto end = s.find_first_of(" \n,<]", at);
        s.replace(at, (end == std::string::npos ? s.size() : end) - at,
                  kDictionary[28 + pick(kDictionary.size() - 28)]);
        break;
      }
      default: {  // a long run of one token (limits: dotted keys, nesting, long lines)
        const auto& tok = kDictionary[pick(12)];
        std::string run;
        for (std::size_t i = 0, n = 10 + pick(3000); i < n; ++i) run += tok;
        s.insert(pick(s.size() + 1), run);
      }
    }
  }
  return s;
}

}  // namespace hapticlab::fuzz
