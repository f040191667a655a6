#pragma once
// FitSummary in JSON and in words, shared by `model fit-contact` and the workbench commands.

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <nlohmann/json.hpp>
#include <string>

#include "hapticlab/modeling/workbench.hpp"

namespace hapticlab::cli {

inline nlohmann::json FitSummaryJson(const modeling::wb::FitSummary& s) {
  return {{"what", modeling::wb::ChannelName(s.channel)},
          {"method", s.method},
          {"termination", modeling::wb::TerminationText(s)},
          {"message", s.message},
          {"iterations", s.iterations},
          {"initial_cost", s.initial_cost},
          {"final_cost", s.final_cost},
          {"at_bounds", s.at_bounds},
          {"usable", s.usable}};
}

inline std::string FitSummaryLine(const modeling::wb::FitSummary& s) {
  std::string line =
      fmt::format("{} fit: {}, {} iterations, cost {:.6g} -> {:.6g}{}",
                  modeling::wb::ChannelName(s.channel), modeling::wb::TerminationText(s),
                  s.iterations, s.initial_cost, s.final_cost, s.usable ? "" : " -- NOT USABLE");
  if (!s.at_bounds.empty()) line += fmt::format("; at a bound: {}", fmt::join(s.at_bounds, ", "));
  return line;
}

/// The friction channel's parametric bootstrap (workbench_bootstrap.hpp) in JSON: whether it was
/// applied (or why not), the noise it measured and simulated, each parameter's fit, bias,
/// corrected value and standard errors.
inline nlohmann::json BootstrapJson(const modeling::wb::BootstrapReport& b) {
  nlohmann::json params = nlohmann::json::array();
  for (const auto& p : b.params)
    params.push_back({{"effect", p.effect},
                      {"name", p.name},
                      {"fit", p.fit},
                      {"bias", p.bias},
                      {"corrected", p.corrected},
                      {"at_bound", p.clamped},
                      {"jackknife_sd", p.jackknife_sd},
                      {"bootstrap_sd", p.bootstrap_sd},
                      {"sd", p.sd}});
  return {{"applied", b.applied},
          {"why_not", b.why_not},
          {"replicates", b.replicates},
          {"noise",
           {{"position_m", b.noise.position_m},
            {"velocity_mps", b.noise.velocity_mps},
            {"tangential_N", b.noise.tangential_N},
            {"load_N", b.noise.load_N}}},
          {"params", params}};
}

/// One line: the correction applied (bias per parameter) or why not.
inline std::string BootstrapLine(const modeling::wb::BootstrapReport& b) {
  if (!b.applied) return "friction bootstrap: not applied (" + b.why_not + ")";
  std::string line = fmt::format("friction bootstrap ({} simulated copies): bias", b.replicates);
  for (const auto& p : b.params)
    line += fmt::format(" {} {:+.3g} ({:+.2f} %{})", p.name, p.bias,
                        p.fit != 0 ? 100 * p.bias / p.fit : 0.0,
                        p.clamped ? fmt::format(", held at its bound {:.6g}", p.corrected) : "");
  return line + ", corrected";
}

}  // namespace hapticlab::cli
