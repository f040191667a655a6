#pragma once
// Shared by the plan, bundle and site code (private to replication).

#include <map>
#include <string>
#include <vector>

#include "hapticlab/replication/plan.hpp"

namespace hapticlab::replication::internal {

// The "file" of an error in what the caller gave (the CLI shows the field as its option).
inline constexpr const char* kCommandLine = "<command line>";

// Largest plan accepted (files, bytes in all): a plan holds text files of a few MB.
inline constexpr std::size_t kMaxPlanFiles = 10000;
inline constexpr std::size_t kMaxPlanBytes = std::size_t{512} << 20;

// A path a plan may hold: relative, '/'-separated, no empty, '.' or '..' part, no backslash,
// no control character; at most 4096 bytes.
bool SafeRelativePath(const std::string& path);

// MANIFEST.sha256 of `files` (path -> bytes): "<sha256>  <path>\n" per file, sorted by path.
std::string ManifestText(const std::map<std::string, std::string>& files);

// Every regular file under `dir` (path relative to it -> bytes). Anything that is not a
// regular file or directory (a link, a device) is reported in *problems as "extra".
// @throws InputError when dir is not a directory or the plan is too large
std::map<std::string, std::string> ReadTree(const std::string& dir,
                                            std::vector<PlanProblem>* problems);

// Writes `files` under `dir` (created), each through WriteTextFile.
void WriteTree(const std::string& dir, const std::map<std::string, std::string>& files);

// Refuses (InputError naming `field`) a directory that exists and is not empty.
void CheckEmptyOutput(const std::string& dir, const std::string& field);

// A gzip-compressed tar of `files` (bundle.hpp), written atomically (a sibling file renamed).
void WriteArchive(const std::map<std::string, std::string>& files, const std::string& out_path);
// The entries of a bundle (path -> bytes). @throws InputError naming the bundle and the entry
// when it is not a tar.gz, an entry is not a regular file, its path is unsafe or repeated,
// or the whole is larger than a plan
std::map<std::string, std::string> ReadArchive(const std::string& path);

// A rig file to fill in for `device`, its opening comment pointing to rig init, rig touch
// and rig calibrate; `whose` says whose rig it is ("this plan", "site LabB").
std::string RigTemplateText(const std::string& device, const std::string& whose);

// A TOML basic string of `s`.
std::string Quote(const std::string& s);

// Letters, digits, '-', '_' of `s` (others become '_'); "x" when empty.
std::string SafeName(const std::string& s);

}  // namespace hapticlab::replication::internal
