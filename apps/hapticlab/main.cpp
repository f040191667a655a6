// hapticlab: the one command line of HapticLab (its commands: app.cpp).

#include <csignal>

#include "app.hpp"

int main(int argc, char** argv) {
  // A file-size limit (ulimit -f) must end in a clear error from the failed write (EFBIG),
  // like a full disk, not in SIGXFSZ killing the process mid-session.
  std::signal(SIGXFSZ, SIG_IGN);
  return hapticlab::cli::RunCli(argc, argv);
}
