#include "hapticlab/protocols/participant_code.hpp"

#include <fmt/format.h>

#include <cctype>
#include <regex>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::protocols {
namespace {

bool PlainChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '_';
}

// The literal characters a pattern's codes start with ("" when it starts with a class,
// group or alternation).
std::string LiteralPrefix(const std::string& pattern) {
  std::size_t i = !pattern.empty() && pattern[0] == '^' ? 1 : 0;
  std::string out;
  while (i < pattern.size()) {
    char c = pattern[i];
    std::size_t next = i + 1;
    if (c == '\\' && i + 1 < pattern.size() && (pattern[i + 1] == '-' || pattern[i + 1] == '_')) {
      c = pattern[i + 1];
      next = i + 2;
    } else if (!PlainChar(c)) {
      break;
    }
    if (next < pattern.size() && (pattern[next] == '?' || pattern[next] == '*' ||
                                  pattern[next] == '+' || pattern[next] == '{'))
      break;  // optional or repeated: not a fixed part of every code
    out += c;
    i = next;
  }
  return out;
}

bool Matches(const Protocol& p, const std::string& code) {
  std::string why;
  return ParticipantCodeAccepted(p, code, &why);
}

long Limit(int digits) {
  long n = 1;
  for (int i = 0; i < digits; ++i) n *= 10;
  return n;  // numbers 1..n-1 fit the width
}

}  // namespace

std::string FormatCode(const CodeFormat& f, long n) {
  return fmt::format("{}{:0{}d}", f.prefix, n, f.digits);
}

CodeFormat InferCodeFormat(const Protocol& p, const std::string& prefix,
                           const std::string& prefix_option) {
  CodeFormat f;
  f.prefix = prefix;
  if (f.prefix.empty()) f.prefix = LiteralPrefix(p.participant_code);
  if (f.prefix.empty()) f.prefix = "P";
  for (const int digits : {2, 3, 4, 5, 6, 1}) {
    f.digits = digits;
    if (Matches(p, FormatCode(f, 1)) || Matches(p, FormatCode(f, Limit(digits - 1)))) return f;
  }
  if (!prefix.empty())
    throw InputError("<command line>", 0, prefix_option,
                     fmt::format("no code '{}' followed by a number of 1-6 digits matches the "
                                 "protocol's participant_code pattern {}",
                                 prefix, p.participant_code));
  throw InputError(p.file, 0, "study.participant_code",
                   fmt::format("cannot tell how codes matching {} are spelled (tried '{}' and a "
                               "number of 1-6 digits); give the letters before the number with {}",
                               p.participant_code, f.prefix, prefix_option));
}

std::string NextFreeCode(const Protocol& p, const CodeFormat& f,
                         const std::set<std::string>& taken) {
  for (long n = 1; n < Limit(f.digits); ++n) {
    std::string code = FormatCode(f, n);
    if (!taken.count(code) && Matches(p, code)) return code;
  }
  throw InputError(p.file, 0, "study.participant_code",
                   fmt::format("every code '{}' + {} digits matching {} is taken", f.prefix,
                               f.digits, p.participant_code));
}

}  // namespace hapticlab::protocols
