#pragma once
/// @file The error policy's primitives (docs/architecture.md, "Errors").
///
/// Three kinds of failure, each with one mechanism:
/// - bad user data (files, arguments, protocols): `hapticlab::InputError`
///   (core/diagnostics.hpp), always with the file (or "<command line>"), the line where one
///   exists, the field and what was expected; the CLI exits 2;
/// - a caller breaking an API's documented precondition (a bug in the calling code):
///   `HL_REQUIRE(cond, message)` throws `hapticlab::PreconditionError`; the CLI exits 1 and
///   calls it an internal error;
/// - the environment failing (I/O, a device, the database, a solver that cannot proceed):
///   `std::runtime_error` (or a subclass); the CLI exits 1.
/// Iterative solvers return a `SolverSummary` (core/solver_summary.hpp) instead of throwing
/// when they do not converge. Real-time ticks throw nothing: they report faults in their
/// counters and command zero force.

#include <stdexcept>
#include <string>

namespace hapticlab {

/// A documented precondition of an API was broken by its caller (a programming error, never
/// bad user input). The message names the source location and the condition.
class PreconditionError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

namespace internal {
[[noreturn]] inline void ThrowPrecondition(const char* file, int line, const char* cond,
                                           const std::string& message) {
  throw PreconditionError(std::string(file) + ":" + std::to_string(line) + ": precondition `" +
                          cond + "` failed: " + message);
}
}  // namespace internal

}  // namespace hapticlab

/// Precondition check at a non-real-time public API: throws hapticlab::PreconditionError.
#define HL_REQUIRE(cond, message)                                                                \
  do {                                                                                           \
    if (!(cond)) ::hapticlab::internal::ThrowPrecondition(__FILE__, __LINE__, #cond, (message)); \
  } while (0)
