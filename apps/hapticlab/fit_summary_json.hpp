#pragma once
// FitSummary in JSON and in words, shared by `model fit-contact` and the workbench commands.

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <nlohmann/json.hpp>
#include <string>

#include "hapticlab/modeling/workbench.hpp"

namespace hapticlab::cli {

inline nlohmann::json FitSummaryJson(const modeling::wb::FitSummary& s) {
  return {{"what", s.what},
          {"method", s.method},
          {"termination", s.termination},
          {"message", s.message},
          {"iterations", s.iterations},
          {"initial_cost", s.initial_cost},
          {"final_cost", s.final_cost},
          {"at_bounds", s.at_bounds},
          {"usable", s.usable}};
}

inline std::string FitSummaryLine(const modeling::wb::FitSummary& s) {
  std::string line =
      fmt::format("{} fit: {}, {} iterations, cost {:.6g} -> {:.6g}{}", s.what, s.termination,
                  s.iterations, s.initial_cost, s.final_cost, s.usable ? "" : " -- NOT USABLE");
  if (!s.at_bounds.empty()) line += fmt::format("; at a bound: {}", fmt::join(s.at_bounds, ", "));
  return line;
}

}  // namespace hapticlab::cli
