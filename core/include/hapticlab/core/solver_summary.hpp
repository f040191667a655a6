#pragma once
/// @file What an iterative solver reports instead of throwing (Ceres' Solver::Summary idea).

#include <string>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab {

/// The outcome of an iterative fit or optimisation. A solver that stops without converging
/// returns normally with `converged == false` and says why in `message`; callers decide.
struct SolverSummary {
  bool converged = false;
  int iterations = 0;
  double initial_cost = 0.0;         ///< objective at the start, in the solver's own units
  double final_cost = 0.0;           ///< objective at the end
  std::string message;               ///< why it stopped ("converged: relative step < 1e-8", ...)
  std::vector<Diagnostic> warnings;  ///< non-fatal problems, with file/field when known

  /// One line: "converged after 41 iterations, cost 3.2 -> 0.11 (reason)".
  std::string BriefReport() const {
    return std::string(converged ? "converged" : "NOT converged") + " after " +
           std::to_string(iterations) + " iterations, cost " + std::to_string(initial_cost) +
           " -> " + std::to_string(final_cost) + (message.empty() ? "" : " (" + message + ")");
  }
};

}  // namespace hapticlab
