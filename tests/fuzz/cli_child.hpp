#pragma once
// Runs the hapticlab command line (cli::RunCli, what main() runs) in a forked child with an
// address-space limit and a wall-clock timeout, and classifies how it ended: the CLI's fuzz
// test (cli_fuzz_test.cpp) runs thousands of inputs this way without paying the binary's
// start-up for each.

#include <sys/types.h>

#include <string>
#include <vector>

namespace hapticlab::fuzz {

struct ChildLimits {
  double timeout_s = 10;   ///< wall clock; the child is killed (SIGKILL) past it
  std::size_t max_as = 0;  ///< RLIMIT_AS in bytes; 0: none (sanitizers reserve terabytes)
};

struct ChildResult {
  int exit_code = -1;  ///< the CLI's exit code, or -1 when it did not exit
  int signal = 0;      ///< the signal that ended it (0: it exited)
  bool timed_out = false;
  double seconds = 0;
  std::string output;  ///< stdout and stderr together (the first 64 KiB)
};

/// A started child: the CLI on `args` (args[0] is the program name), its output to `log`.
struct Child {
  pid_t pid = -1;
  double started = 0;  ///< steady-clock seconds
  std::string log;
};
Child StartCli(const std::vector<std::string>& args, const std::string& log,
               const ChildLimits& limits);

/// Waits for `c` (killing it past the timeout) and collects how it ended.
ChildResult Finish(const Child& c, const ChildLimits& limits);

/// Library text or SQL in the CLI's output that must never reach a user, or "" when none.
std::string ForbiddenText(const std::string& output);

/// The test process's own address-space size (bytes), the base of the RLIMIT_AS bound.
std::size_t OwnAddressSpace();

/// True in the sanitizer builds (CMake defines HL_FUZZ_SANITIZED with HL_SANITIZE).
#ifdef HL_FUZZ_SANITIZED
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

/// The limits the CLI fuzz tests run their children under: `timeout_s` (five times it under
/// the sanitizers), and 1 GiB of address space beyond what the forked test process already
/// maps (no bound under the sanitizers).
ChildLimits CliLimits(double timeout_s);

}  // namespace hapticlab::fuzz
