#pragma once
/// @file Assertion and argument-check macros (STYLE.md §6).

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

/// Always-on invariant check: aborts with file:line when `cond` is false.
#define HL_DEMAND(cond)                                                              \
  do {                                                                               \
    if (!(cond)) {                                                                   \
      std::fprintf(stderr, "%s:%d: HL_DEMAND(%s) failed\n", __FILE__, __LINE__, #cond); \
      std::abort();                                                                  \
    }                                                                                \
  } while (0)

#ifndef NDEBUG
#define HL_ASSERT(cond) HL_DEMAND(cond)
#else
#define HL_ASSERT(cond) ((void)0)
#endif

/// Argument check at a non-real-time public API: throws std::invalid_argument.
#define HL_THROW_UNLESS(cond, msg)                                   \
  do {                                                               \
    if (!(cond)) throw std::invalid_argument(std::string(msg));      \
  } while (0)
