// db merge: conflict checks over the inputs, then the atomic build (merge_copy.cpp copies).
#include "hapticlab/db/merge.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "merge_internal.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db {

namespace fs = std::filesystem;
using internal::Stmt;

std::string SiteQualifiedCode(const std::string& site, const std::string& code) {
  return code.find(':') != std::string::npos ? code : site + ":" + code;
}

namespace {

// What the checks need of one input.
struct InputInfo {
  std::string path;
  std::map<std::string, std::string> protocols;  // study name -> protocol identity
  // (study, site-qualified code) -> site of the participant's sessions
  std::map<std::pair<std::string, std::string>, std::string> participants;
  std::set<std::string> plans;  // plan hashes of its sessions ("" = no plan)
  int reserved = 0;
  std::string order_key;  // smallest "study\x1fqualified code"
};

std::string CodeAfterSite(const std::string& qualified) {
  return qualified.substr(qualified.find(':') + 1);
}

InputInfo Inspect(const std::string& path) {
  const Database d = OpenForReading(path);  // quick_check; older files migrated forward
  InputInfo in;
  in.path = path;
  for (const auto& st : d.Studies()) {
    in.protocols[st.name] =
        st.protocol_canonical_sha256.empty() ? st.protocol_hash : st.protocol_canonical_sha256;
    for (const auto& p : d.Participants(st.id)) {
      const auto sessions = d.Sessions(p.id);
      if (sessions.empty()) {
        ++in.reserved;
        continue;
      }
      std::string site = sessions.front().site_code;
      for (const auto& se : sessions) {
        site = std::min(site, se.site_code);
        const auto prov = nlohmann::json::parse(se.provenance_json, nullptr, false);
        in.plans.insert(prov.is_object() && prov.contains("plan_sha256") &&
                                prov["plan_sha256"].is_string()
                            ? prov["plan_sha256"].get<std::string>()
                            : std::string());
      }
      const std::string q = SiteQualifiedCode(site, p.code);
      in.participants[{st.name, q}] = q.substr(0, q.find(':'));
      const std::string key = st.name + "\x1f" + q;
      if (in.order_key.empty() || key < in.order_key) in.order_key = key;
    }
  }
  return in;
}

[[noreturn]] void Conflict(const std::string& a, const std::string& b, const std::string& what) {
  throw InputError(a, 0, "db merge", fmt::format("conflicts with {}: {}", b, what));
}

std::string PlanName(const std::string& h) { return h.empty() ? "no plan" : "plan " + h; }

void CheckConflicts(const std::vector<InputInfo>& ins, const MergeOptions& o) {
  // (study, qualified code) -> input; (study, bare code) -> (site, input)
  std::map<std::pair<std::string, std::string>, const InputInfo*> seen;
  std::map<std::pair<std::string, std::string>, std::pair<std::string, const InputInfo*>> bare;
  std::map<std::string, std::pair<std::string, const InputInfo*>> protocol;
  std::pair<std::string, const InputInfo*> plan{"", nullptr};
  for (const auto& in : ins) {
    for (const auto& [study, id] : in.protocols) {
      const auto [it, fresh] = protocol.try_emplace(study, id, &in);
      if (!fresh && it->second.first != id && !o.allow_different_protocols)
        Conflict(it->second.second->path, in.path,
                 fmt::format("study '{}' was run with different protocols (canonical SHA-256 {} "
                             "and {}); --allow-different-protocols merges them anyway",
                             study, it->second.first, id));
    }
    for (const auto& [key, site] : in.participants) {
      if (const auto it = seen.find(key); it != seen.end())
        Conflict(it->second->path, in.path,
                 fmt::format("both hold participant {} of study '{}' (the same database twice, "
                             "or one participant recorded in two databases); refused",
                             key.second, key.first));
      seen[key] = &in;
      const std::pair<std::string, std::string> b{key.first, CodeAfterSite(key.second)};
      const auto [it, fresh] = bare.try_emplace(b, site, &in);
      if (!fresh && it->second.first != site && !o.allow_shared_codes)
        Conflict(it->second.second->path, in.path,
                 fmt::format("participant code {} of study '{}' is used at sites {} and {} (one "
                             "person at two sites?); --allow-shared-codes keeps them as two "
                             "participants ({} and {})",
                             b.second, b.first, it->second.first, site,
                             SiteQualifiedCode(it->second.first, b.second),
                             SiteQualifiedCode(site, b.second)));
    }
    for (const auto& h : in.plans) {
      if (!plan.second) plan = {h, &in};
      if (h != plan.first && !o.allow_different_plans)
        Conflict(plan.second->path, in.path,
                 fmt::format("sessions were recorded under different plans ({} and {}); "
                             "--allow-different-plans merges them anyway (the analysis reports "
                             "it as a deviation)",
                             PlanName(plan.first), PlanName(h)));
    }
  }
}

void CheckPaths(const std::vector<std::string>& inputs, const std::string& output) {
  if (inputs.size() < 2)
    throw InputError("<command line>", 0, "INPUTS", "db merge needs two or more databases");
  std::error_code ec;
  const fs::path folder = fs::absolute(output).parent_path();
  if (!fs::is_directory(folder, ec)) throw InputError(output, 0, "-o", "its folder does not exist");
  if (fs::exists(output, ec) || fs::is_symlink(output, ec))
    throw InputError(output, 0, "-o", "already exists; a merge never overwrites a file");
  for (const auto& in : inputs)
    if (!fs::is_regular_file(in, ec)) throw InputError(in, 0, "db", "no such database file");
  for (std::size_t i = 0; i < inputs.size(); ++i)
    for (std::size_t j = i + 1; j < inputs.size(); ++j)
      if (fs::equivalent(inputs[i], inputs[j], ec))
        Conflict(inputs[i], inputs[j],
                 "they are the same file; a database is never merged "
                 "with itself");
}

// The file of an exclusive advisory lock, kept for the merge's life: a second merge into the
// same output is refused instead of sharing its scratch files.
class ScratchLock {
 public:
  explicit ScratchLock(const std::string& path)
      : fd_(::open(path.c_str(), O_RDWR | O_CREAT, 0644)) {
    if (fd_ < 0)
      throw std::runtime_error(path +
                               ": cannot create the merge's scratch file: " + std::strerror(errno));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw std::runtime_error(path + ": another merge into this output is running");
    }
  }
  ~ScratchLock() { ::close(fd_); }
  ScratchLock(const ScratchLock&) = delete;
  ScratchLock& operator=(const ScratchLock&) = delete;
  int fd() const { return fd_; }

 private:
  int fd_;
};

void RemoveDbFiles(const std::string& path) {
  std::error_code ec;
  for (const char* suffix : {"", "-wal", "-shm", "-journal"}) fs::remove(path + suffix, ec);
}

void SyncDirectory(const std::string& file) {
  const std::string dir = fs::absolute(file).parent_path().string();
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    (void)::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

MergeSummary MergeDatabases(const std::vector<std::string>& inputs, const std::string& output,
                            const MergeOptions& options) {
  CheckPaths(inputs, output);
  std::vector<InputInfo> ins;
  for (const auto& path : inputs) ins.push_back(Inspect(path));
  // The order of the output's rows: by content, never by the order given.
  std::stable_sort(ins.begin(), ins.end(), [](const InputInfo& a, const InputInfo& b) {
    return a.order_key < b.order_key;
  });
  CheckConflicts(ins, options);

  const std::string scratch = output + ".merging", build_path = output + ".merging-build";
  const ScratchLock lock(scratch);
  if (::ftruncate(lock.fd(), 0) != 0)  // what a killed merge left
    throw std::runtime_error(scratch + ": cannot empty it: " + std::strerror(errno));
  RemoveDbFiles(build_path);
  MergeSummary sum;
  {
    Database build(build_path);
    internal::ExecSql(build.handle(), "PRAGMA synchronous = OFF");  // scratch: rebuilt on rerun
    for (std::size_t i = 0; i < ins.size(); ++i)
      internal::CopyInput(build.handle(), ins[i].path, /*first=*/i == 0);
    // A rollback-journal file: read without a -wal or -shm beside it (a writer turns WAL on).
    internal::ExecSql(build.handle(), "PRAGMA journal_mode = DELETE");
    Stmt vacuum(build.handle(), "VACUUM INTO ?");
    vacuum.Bind(1, scratch).Run();
  }
  RemoveDbFiles(build_path);
  {
    const Database out(scratch, {.create = false, .read_only = true});
    if (const auto check = out.IntegrityCheck(); check != "ok")
      throw std::runtime_error(scratch +
                               ": the merged file fails SQLite's integrity check: " + check);
    Stmt fk(out.handle(), "SELECT count(*) FROM pragma_foreign_key_check");
    if (fk.Step() && fk.Int(0) != 0)
      throw std::runtime_error(scratch + ": the merged file has rows pointing at nothing");
    sum = internal::Summarize(out.handle());
  }
  for (const auto& in : ins) sum.reserved_left_out += in.reserved;
  if (::fsync(lock.fd()) != 0)
    throw std::runtime_error(scratch + ": cannot sync it: " + std::strerror(errno));
  // link() refuses an existing name: an output that appeared meanwhile is never replaced.
  if (::link(scratch.c_str(), output.c_str()) != 0)
    throw InputError(output, 0, "-o", std::string("cannot create it: ") + std::strerror(errno));
  ::unlink(scratch.c_str());
  SyncDirectory(output);
  return sum;
}

}  // namespace hapticlab::db
