#pragma once
// A few CLI children at a time (cli_child.hpp), each in a slot folder of its own, with every
// outcome checked: no signal, no timeout, the exit codes allowed, no library text or SQL.

#include <functional>
#include <string>
#include <vector>

#include "cli_child.hpp"

namespace hapticlab::fuzz {

/// One run of the CLI. `args` excludes the program name.
struct Job {
  std::vector<std::string> args;
  std::string input;               ///< the fuzzed bytes, saved with a finding to reproduce it
  std::vector<int> allowed{0, 2};  ///< exit codes that are not findings
  std::vector<std::string> not_in_output;  ///< text that must not appear besides ForbiddenText
};

class Pool {
 public:
  /// `slots` children at once; their folders are created under `dir`.
  Pool(int slots, const ChildLimits& limits, const std::string& dir);

  /// Runs `n` jobs; `make(i, slot_dir)` writes job i's files into slot_dir and returns it.
  /// Returns the findings, one line each (at most 20 kept in full; the input of each is saved
  /// under `findings_dir` when that is not empty).
  std::vector<std::string> Run(int n, const std::function<Job(int, const std::string&)>& make,
                               const std::string& label, const std::string& findings_dir);

  double slowest_s() const { return slowest_s_; }

 private:
  ChildLimits limits_;
  std::vector<std::string> slots_;
  double slowest_s_ = 0;
};

}  // namespace hapticlab::fuzz
