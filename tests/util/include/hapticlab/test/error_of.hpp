#pragma once
// The one diagnostic of an InputError a call throws (shared by the tests that check messages).

#include <gtest/gtest.h>

#include <string>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::test {

/// Calls `f`, expects it to throw an InputError with exactly one diagnostic and returns it
/// (a test failure and an empty diagnostic otherwise).
template <typename F>
Diagnostic ErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    EXPECT_EQ(e.diagnostics().size(), 1u);
    if (!e.diagnostics().empty()) return e.diagnostics()[0];
  }
  ADD_FAILURE() << "no InputError";
  return {};
}

/// "file|line|field" of the first diagnostic of the InputError `f` throws, or "no error" when
/// it throws none: a test compares the place a refusal names in one string.
template <typename F>
std::string WhereOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    const auto& d = e.diagnostics().at(0);
    return d.file + "|" + std::to_string(d.line) + "|" + d.field;
  }
  return "no error";
}

}  // namespace hapticlab::test
