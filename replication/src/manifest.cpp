// The plan's manifest: writing it, reading it back, checking files against it.

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <sstream>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/db/database.hpp"
#include "plan_internal.hpp"

namespace hapticlab::replication {
namespace internal {

namespace fs = std::filesystem;

bool SafeRelativePath(const std::string& path) {
  if (path.empty() || path.size() > 4096 || path.front() == '/' || path.back() == '/') return false;
  for (const char c : path)
    if (static_cast<unsigned char>(c) < 0x20 || c == '\\' || c == 0x7f) return false;
  std::size_t start = 0;
  while (start <= path.size()) {
    const auto slash = path.find('/', start);
    const auto part =
        path.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    if (part.empty() || part == "." || part == "..") return false;
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
  return true;
}

std::string ManifestText(const std::map<std::string, std::string>& files) {
  std::string out;  // std::map iterates in byte order of the paths
  for (const auto& [path, bytes] : files) out += db::HashText(bytes) + "  " + path + "\n";
  return out;
}

std::map<std::string, std::string> ReadTree(const std::string& dir,
                                            std::vector<PlanProblem>* problems) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(dir, 0, "", "no such plan directory");
  std::map<std::string, std::string> files;
  std::size_t bytes = 0;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::end(it);
       it.increment(ec)) {
    const auto rel = it->path().lexically_relative(dir).generic_string();
    const auto st = it->symlink_status(ec);
    if (fs::is_directory(st)) continue;
    if (!fs::is_regular_file(st)) {
      problems->push_back({rel, "extra", "not a regular file (a link or a device)"});
      continue;
    }
    if (files.size() >= kMaxPlanFiles)
      throw InputError(dir, 0, "", fmt::format("more than {} files: not a plan", kMaxPlanFiles));
    auto text = ReadTextFile(it->path().string(), "plan file", kMaxPlanBytes);
    bytes += text.size();
    if (bytes > kMaxPlanBytes)
      throw InputError(dir, 0, "",
                       fmt::format("more than {} MiB: not a plan", kMaxPlanBytes >> 20));
    files.emplace(rel, std::move(text));
  }
  if (ec) throw std::runtime_error(dir + ": cannot list the plan directory (" + ec.message() + ")");
  return files;
}

void WriteTree(const std::string& dir, const std::map<std::string, std::string>& files) {
  for (const auto& [path, bytes] : files) {
    const fs::path p = fs::path(dir) / path;
    fs::create_directories(p.parent_path());
    WriteTextFile(p.string(), bytes);
  }
}

void CheckEmptyOutput(const std::string& dir, const std::string& field) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !(fs::is_directory(dir, ec) && fs::is_empty(dir, ec)))
    throw InputError(dir, 0, field,
                     "exists and is not an empty directory: a plan is written into a new one");
}

std::string SafeName(const std::string& s) {
  std::string out;
  for (const char c : s)
    out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  return out.empty() ? "x" : out;
}

}  // namespace internal

namespace {

bool IsHex64(const std::string& s) {
  return s.size() == 64 && std::all_of(s.begin(), s.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

std::string Short(const std::string& hash) { return hash.substr(0, 16); }

// Parses MANIFEST.sha256 into path -> hash; a malformed line is a problem of the manifest.
std::map<std::string, std::string> ParseManifest(const std::string& text,
                                                 std::vector<PlanProblem>* problems) {
  std::map<std::string, std::string> out;
  std::istringstream in(text);
  std::string line, previous;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    const std::string hash = line.substr(0, 64), path = line.size() > 66 ? line.substr(66) : "";
    if (line.size() < 67 || !IsHex64(hash) || line.compare(64, 2, "  ") != 0 ||
        !internal::SafeRelativePath(path)) {
      problems->push_back({kManifestFile, "malformed",
                           fmt::format("line {}: expected '<64 hex digits>  <relative path>'", n)});
      continue;
    }
    if (!previous.empty() && path <= previous)
      problems->push_back(
          {kManifestFile, "malformed", fmt::format("line {}: paths not sorted or repeated", n)});
    previous = path;
    out[path] = hash;
  }
  if (!text.empty() && text.back() != '\n')
    problems->push_back({kManifestFile, "malformed", "the last line has no newline"});
  return out;
}

}  // namespace

std::string VerifyResult::Describe() const {
  std::string out;
  for (const auto& p : problems) out += p.kind + ": " + p.path + " (" + p.detail + ")\n";
  return out;
}

VerifyResult VerifyFiles(const std::map<std::string, std::string>& files) {
  VerifyResult r;
  const auto manifest = files.find(kManifestFile);
  const auto hash_file = files.find(kPlanHashFile);
  if (manifest == files.end()) {
    r.problems.push_back({kManifestFile, "missing", "the plan's list of files and hashes"});
    return r;
  }
  r.plan_hash = db::HashText(manifest->second);
  if (hash_file == files.end()) {
    r.problems.push_back({kPlanHashFile, "missing", "the plan hash"});
  } else {
    const std::string& text = hash_file->second;
    const std::string expected = r.plan_hash + "  " + kManifestFile + "\n";
    if (text != expected)
      r.problems.push_back(
          {kPlanHashFile, "changed",
           text.size() == expected.size() && IsHex64(text.substr(0, 64)) &&
                   text.substr(64) == expected.substr(64)
               ? fmt::format("it records plan hash {}, but {} hashes to {}: one of the two "
                             "changed (compare with the deposited plan hash)",
                             Short(text), kManifestFile, Short(r.plan_hash))
               : fmt::format("expected one line '<plan hash>  {}'", kManifestFile)});
  }
  const auto listed = ParseManifest(manifest->second, &r.problems);
  r.files = listed.size();
  for (const auto& [path, hash] : listed) {
    const auto f = files.find(path);
    if (f == files.end()) {
      r.problems.push_back({path, "missing", "listed in " + std::string(kManifestFile)});
      continue;
    }
    const auto found = db::HashText(f->second);
    if (found != hash)
      r.problems.push_back(
          {path, "changed", fmt::format("sha256 {}, manifest {}", Short(found), Short(hash))});
  }
  for (const auto& [path, bytes] : files)
    if (path != kManifestFile && path != kPlanHashFile && !listed.count(path))
      r.problems.push_back({path, "extra", "not listed in " + std::string(kManifestFile)});
  return r;
}

VerifyResult VerifyPlan(const std::string& dir) {
  std::vector<PlanProblem> special;
  const auto files = internal::ReadTree(dir, &special);
  auto r = VerifyFiles(files);
  r.problems.insert(r.problems.end(), special.begin(), special.end());
  return r;
}

}  // namespace hapticlab::replication
