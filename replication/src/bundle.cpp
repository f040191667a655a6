// Replication bundles: a plan as one reproducible tar.gz, written and read with libarchive
// (replication/bundle.hpp).

#include "hapticlab/replication/bundle.hpp"

#include <archive.h>
#include <archive_entry.h>
#include <fmt/format.h>

#include <filesystem>
#include <memory>

#include "hapticlab/core/diagnostics.hpp"
#include "plan_internal.hpp"

namespace hapticlab::replication {
namespace internal {

namespace fs = std::filesystem;

namespace {

struct ArchiveWriteFree {
  void operator()(archive* a) const { archive_write_free(a); }
};
struct ArchiveReadFree {
  void operator()(archive* a) const { archive_read_free(a); }
};
struct EntryFree {
  void operator()(archive_entry* e) const { archive_entry_free(e); }
};

}  // namespace

void WriteArchive(const std::map<std::string, std::string>& files, const std::string& out_path) {
  const std::string tmp = out_path + ".writing";
  {
    std::unique_ptr<archive, ArchiveWriteFree> a(archive_write_new());
    if (!a) throw std::runtime_error(out_path + ": out of memory");
    const auto check = [&](int r) {
      if (r != ARCHIVE_OK)
        throw std::runtime_error(out_path + ": cannot write the bundle (" +
                                 archive_error_string(a.get()) + ")");
    };
    check(archive_write_set_format_pax_restricted(a.get()));
    check(archive_write_add_filter_gzip(a.get()));
    // No time stamp in the gzip header: the same plan gives the same bytes.
    check(archive_write_set_filter_option(a.get(), "gzip", "timestamp", nullptr));
    check(archive_write_open_filename(a.get(), tmp.c_str()));
    for (const auto& [path, bytes] : files) {
      std::unique_ptr<archive_entry, EntryFree> e(archive_entry_new());
      archive_entry_set_pathname(e.get(), path.c_str());
      archive_entry_set_size(e.get(), static_cast<la_int64_t>(bytes.size()));
      archive_entry_set_filetype(e.get(), AE_IFREG);
      archive_entry_set_perm(e.get(), 0644);
      archive_entry_set_mtime(e.get(), 0, 0);
      archive_entry_set_uid(e.get(), 0);
      archive_entry_set_gid(e.get(), 0);
      check(archive_write_header(a.get(), e.get()));
      if (!bytes.empty() && archive_write_data(a.get(), bytes.data(), bytes.size()) !=
                                static_cast<la_ssize_t>(bytes.size()))
        check(ARCHIVE_FATAL);
    }
    check(archive_write_close(a.get()));
  }
  std::error_code ec;
  fs::rename(tmp, out_path, ec);
  if (ec) throw std::runtime_error(out_path + ": cannot write the bundle (" + ec.message() + ")");
}

std::map<std::string, std::string> ReadArchive(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path, 0, "", "no such bundle file");
  std::unique_ptr<archive, ArchiveReadFree> a(archive_read_new());
  if (!a) throw std::runtime_error(path + ": out of memory");
  archive_read_support_filter_gzip(a.get());
  archive_read_support_format_tar(a.get());
  const auto not_bundle = [&](const std::string& what) {
    return InputError(path, 0, "",
                      "not a HapticLab bundle (expected a gzip-compressed tar of a plan): " + what);
  };
  if (archive_read_open_filename(a.get(), path.c_str(), 1 << 16) != ARCHIVE_OK)
    throw not_bundle("cannot open it as one");
  std::map<std::string, std::string> files;
  std::size_t total = 0;
  archive_entry* e = nullptr;
  int r;
  while ((r = archive_read_next_header(a.get(), &e)) == ARCHIVE_OK) {
    const char* name = archive_entry_pathname(e);
    std::string entry = name ? name : "";
    while (entry.rfind("./", 0) == 0) entry.erase(0, 2);  // tar -C DIR . writes "./path"
    if (archive_entry_filetype(e) == AE_IFDIR) continue;
    if (archive_entry_filetype(e) != AE_IFREG)
      throw InputError(path, 0, entry,
                       "a bundle holds regular files only (this is a link or "
                       "a device)");
    if (!SafeRelativePath(entry))
      throw InputError(path, 0, entry,
                       "unsafe path (absolute, '..', or empty part): a bundle's files stay "
                       "inside the directory it is imported into");
    if (files.count(entry)) throw InputError(path, 0, entry, "appears twice in the bundle");
    const auto size = archive_entry_size(e);
    if (size < 0 || static_cast<std::size_t>(size) > kMaxPlanBytes - total ||
        files.size() >= kMaxPlanFiles)
      throw not_bundle(fmt::format("larger than a plan ({} files, {} MiB at most)", kMaxPlanFiles,
                                   kMaxPlanBytes >> 20));
    std::string bytes(static_cast<std::size_t>(size), '\0');
    std::size_t got = 0;
    while (got < bytes.size()) {
      const auto n = archive_read_data(a.get(), bytes.data() + got, bytes.size() - got);
      if (n <= 0) throw not_bundle("entry '" + entry + "' is cut short");
      got += static_cast<std::size_t>(n);
    }
    total += bytes.size();
    files.emplace(entry, std::move(bytes));
  }
  if (r != ARCHIVE_EOF)
    throw not_bundle("damaged after " + std::to_string(files.size()) + " files");
  return files;
}

}  // namespace internal

std::string WriteBundle(const std::string& plan_dir, const std::string& out_path) {
  std::vector<PlanProblem> special;
  const auto files = internal::ReadTree(plan_dir, &special);
  auto v = VerifyFiles(files);
  v.problems.insert(v.problems.end(), special.begin(), special.end());
  if (!v.ok()) {
    Diagnostics d;
    for (const auto& p : v.problems)
      d.Add((std::filesystem::path(plan_dir) / p.path).string(), 0, p.kind, p.detail);
    d.ThrowIfAny();
  }
  internal::WriteArchive(files, out_path);
  return v.plan_hash;
}

}  // namespace hapticlab::replication
