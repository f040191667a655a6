#include "hapticlab/core/participant_code.hpp"

#include <cctype>
#include <cstddef>

namespace hapticlab {

std::string PseudonymousCodeProblem(const std::string& code) {
  if (code.empty() || code.size() > 32) return "expected 1-32 characters";
  std::size_t digits = 0, letter_run = 0, longest_letters = 0;
  for (unsigned char c : code) {
    if (!std::isalnum(c) && c != '-' && c != '_')
      return "only letters, digits, '-' and '_' are allowed";
    letter_run = std::isalpha(c) ? letter_run + 1 : 0;
    if (letter_run > longest_letters) longest_letters = letter_run;
    if (std::isdigit(c)) ++digits;
  }
  if (digits == 0) return "a code needs at least one digit";
  if (longest_letters > 3) return "more than 3 letters in a row could be a name";
  if (digits > 5) return "more than 5 digits could be a birth date or a phone number";
  // A day and a month: a group of 1-2 digits, '-' or '_', a group of 1-2 digits.
  auto digit_group = [&](std::size_t from, int dir) {
    std::size_t n = 0;
    for (auto i = static_cast<std::ptrdiff_t>(from);
         i >= 0 && i < static_cast<std::ptrdiff_t>(code.size()) &&
         std::isdigit(static_cast<unsigned char>(code[static_cast<std::size_t>(i)]));
         i += dir)
      ++n;
    return n;
  };
  for (std::size_t i = 1; i + 1 < code.size(); ++i)
    if (code[i] == '-' || code[i] == '_') {
      const std::size_t before = digit_group(i - 1, -1), after = digit_group(i + 1, +1);
      if (before >= 1 && before <= 2 && after >= 1 && after <= 2)
        return "digit groups joined by '-' or '_' look like a date";
    }
  return "";
}

}  // namespace hapticlab
