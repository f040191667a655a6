#pragma once
/// @file The shape every participant code must have, whatever a protocol's pattern allows
/// (docs/studies.md, "Participant codes"): the database refuses anything else.

#include <string>

namespace hapticlab {

/// Empty when `code` is a pseudonymous participant code; else why it is not. A code is 1-32
/// letters, digits, '-' or '_' with at least one digit, and has no shape of a name, a date, a
/// phone number or an e-mail address: no run of more than 3 letters, at most 5 digits in all,
/// no day-month shape (1-2 digits, '-' or '_', 1-2 digits); '@' and '.' are not allowed.
std::string PseudonymousCodeProblem(const std::string& code);

/// The rule above in one sentence, for messages that ask for a code again.
inline constexpr const char* kPseudonymousCodeRule =
    "1-32 letters, digits, '-' or '_' with at least one digit, no more than 3 letters in a "
    "row, at most 5 digits and no date-like digit groups; never a name";

}  // namespace hapticlab
