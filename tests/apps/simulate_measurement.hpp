#pragma once
// A measurement for the CLI tests that fit, compare or diagnose models on one: written by
// `hapticlab measurement simulate` itself (modeling/workbench_sim.hpp), as a user makes one.

#include <string>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::test {

/// Runs `hapticlab measurement simulate ARGS -o path`; its exit status, with its stderr in
/// *output for the failure message (its report on stdout is discarded).
inline int SimulateMeasurement(const std::string& args, const std::string& path,
                               std::string* output) {
  return RunCommand("{ " + std::string(HL_CLI_PATH) + " measurement simulate " + args + " -o " +
                        path + " > /dev/null; }",
                    output);
}

}  // namespace hapticlab::test
