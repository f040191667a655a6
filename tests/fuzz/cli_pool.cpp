#include "cli_pool.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <optional>

namespace hapticlab::fuzz {
namespace {

std::string Describe(const ChildResult& r, const Job& j) {
  std::string what;
  if (r.timed_out)
    what = "hang (killed after the timeout)";
  else if (r.signal != 0)
    what = "signal " + std::to_string(r.signal);
  else if (std::find(j.allowed.begin(), j.allowed.end(), r.exit_code) == j.allowed.end())
    what = "exit " + std::to_string(r.exit_code);
  else if (const std::string t = ForbiddenText(r.output); !t.empty())
    what = "library text or SQL in the output ('" + t + "')";
  for (const auto& t : j.not_in_output)
    if (what.empty() && r.output.find(t) != std::string::npos) what = "'" + t + "' in the output";
  if (what.empty()) return "";
  std::string cmd;
  for (const auto& a : j.args) cmd += " " + (a.size() > 80 ? a.substr(0, 80) + "..." : a);
  return what + ":" + cmd + "\n    output: " + r.output.substr(0, 600);
}

}  // namespace

Pool::Pool(int slots, const ChildLimits& limits, const std::string& dir) : limits_(limits) {
  for (int i = 0; i < slots; ++i) {
    slots_.push_back(dir + "/slot" + std::to_string(i));
    std::filesystem::create_directories(slots_.back());
  }
}

std::vector<std::string> Pool::Run(int n, const std::function<Job(int, const std::string&)>& make,
                                   const std::string& label, const std::string& findings_dir) {
  struct Running {
    Child child;
    Job job;
    int index = 0;
  };
  std::vector<std::optional<Running>> running(slots_.size());
  std::vector<std::string> findings;
  int next = 0, done = 0;
  auto collect = [&](std::size_t s) {
    const ChildResult r = Finish(running[s]->child, limits_);
    slowest_s_ = std::max(slowest_s_, r.seconds);
    if (const std::string f = Describe(r, running[s]->job); !f.empty()) {
      if (!findings_dir.empty()) {
        std::filesystem::create_directories(findings_dir);
        std::ofstream(findings_dir + "/" + label + "_" + std::to_string(running[s]->index),
                      std::ios::binary)
            << running[s]->job.input;
      }
      findings.push_back(label + " #" + std::to_string(running[s]->index) + ": " + f);
    }
    running[s].reset();
    ++done;
  };
  while (done < n) {
    for (std::size_t s = 0; s < slots_.size(); ++s) {
      if (!running[s] && next < n) {
        // A clean slot: what the previous job wrote there is gone.
        std::filesystem::remove_all(slots_[s]);
        std::filesystem::create_directories(slots_[s]);
        Job job = make(next, slots_[s]);
        std::vector<std::string> args{"hapticlab"};
        args.insert(args.end(), job.args.begin(), job.args.end());
        running[s] = Running{StartCli(args, slots_[s] + ".log", limits_), std::move(job), next};
        ++next;
      }
    }
    // The oldest running child first: Finish waits for it (up to the timeout).
    std::size_t oldest = slots_.size();
    for (std::size_t s = 0; s < slots_.size(); ++s)
      if (running[s] &&
          (oldest == slots_.size() || running[s]->child.started < running[oldest]->child.started))
        oldest = s;
    if (oldest < slots_.size()) collect(oldest);
  }
  return findings;
}

}  // namespace hapticlab::fuzz
