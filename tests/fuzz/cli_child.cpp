#include "cli_child.hpp"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <thread>

#include "app.hpp"

namespace hapticlab::fuzz {
namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

Child StartCli(const std::vector<std::string>& args, const std::string& log,
               const ChildLimits& limits) {
  // Nothing buffered may be written twice (once by the child's exit path).
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  Child c{.pid = -1, .started = Now(), .log = log};
  c.pid = ::fork();
  if (c.pid < 0) return c;
  if (c.pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::close(fd);
    }
    const int in = ::open("/dev/null", O_RDONLY);
    if (in >= 0) ::dup2(in, 0);
    std::signal(SIGXFSZ, SIG_IGN);  // as main() does
    if (limits.max_as > 0) {
      const rlimit as{limits.max_as, limits.max_as};
      ::setrlimit(RLIMIT_AS, &as);
    }
    // A second guard besides the parent's SIGKILL: CPU time past the timeout ends it too.
    const auto cpu = static_cast<rlim_t>(limits.timeout_s) + 2;
    const rlimit cpu_limit{cpu, cpu};
    ::setrlimit(RLIMIT_CPU, &cpu_limit);
    std::vector<const char*> argv;
    for (const auto& a : args) argv.push_back(a.c_str());
    argv.push_back(nullptr);
    const int rc = cli::RunCli(static_cast<int>(args.size()), argv.data());
    std::cout.flush();
    std::fflush(nullptr);
    ::_exit(rc);  // no static destructors: the parent's objects are not the child's to tear down
  }
  return c;
}

ChildResult Finish(const Child& c, const ChildLimits& limits) {
  ChildResult r;
  if (c.pid < 0) {
    r.output = "fork failed";
    return r;
  }
  int status = 0;
  for (;;) {
    const pid_t w = ::waitpid(c.pid, &status, WNOHANG);
    if (w == c.pid) break;
    if (Now() - c.started > limits.timeout_s) {
      r.timed_out = true;
      ::kill(c.pid, SIGKILL);
      ::waitpid(c.pid, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  r.seconds = Now() - c.started;
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  std::ifstream f(c.log, std::ios::binary);
  r.output.resize(64 << 10);
  f.read(r.output.data(), static_cast<std::streamsize>(r.output.size()));
  r.output.resize(static_cast<std::size_t>(f.gcount()));
  return r;
}

std::string ForbiddenText(const std::string& output) {
  // What the C++ library, nlohmann::json, SQLite statements and precondition checks say:
  // none of it is a message for a user (docs/architecture.md, "Errors").
  static const char* const kForbidden[] = {
      "map::at",        "vector::",       "basic_string", "stoul",
      "stoi",           "stod",           "stoll",        "bad_alloc",
      "json.exception", "internal error", "precondition", "terminate called",
      "prepare '",      "SELECT ",        "INSERT INTO",  "UPDATE ",
      "CREATE TABLE",   "(in: ",          "std::",        "filesystem error",
  };
  for (const char* s : kForbidden)
    if (output.find(s) != std::string::npos) return s;
  return "";
}

std::size_t OwnAddressSpace() {
  std::ifstream f("/proc/self/statm");
  std::size_t pages = 0;
  f >> pages;
  return pages * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
}

ChildLimits CliLimits(double timeout_s) {
  constexpr double kSanitizerSlowdown = 5;
  return {.timeout_s = kSanitized ? kSanitizerSlowdown * timeout_s : timeout_s,
          .max_as = kSanitized ? 0 : OwnAddressSpace() + (std::size_t{1} << 30)};
}

}  // namespace hapticlab::fuzz
