// hapticlab db: copies of a study database that are safe while a session writes to it.

#include <fmt/core.h>

#include <filesystem>
#include <memory>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"

namespace hapticlab::cli {

void RegisterDb(CLI::App& app) {
  auto* group =
      app.add_subcommand("db", "Study database files: an online backup (docs/studies.md)");
  group->require_subcommand(1);
  struct O {
    std::string src, dest;
  };
  auto o = std::make_shared<O>();
  auto* cmd = group->add_subcommand(
      "backup",
      "Copy a study database with SQLite's online backup API: one consistent snapshot of every\n"
      "committed transaction, the -wal file's included, even while 'study run' writes to it.\n"
      "(Copying study.db with cp can miss the ratings still in study.db-wal.) DEST must not "
      "exist.");
  cmd->add_option("SRC", o->src, "Study database")->required();
  cmd->add_option("DEST", o->dest, "New file for the copy (never overwritten)")->required();
  cmd->callback([o] {
    RunGuarded([&] {
      std::error_code ec;  // a path that cannot be looked up is not there
      if (!std::filesystem::is_regular_file(o->src, ec))
        throw InputError(o->src, 0, "SRC", "no such database file");
      if (std::filesystem::exists(o->dest, ec))
        throw InputError(o->dest, 0, "DEST", "already exists; a backup never overwrites a file");
      const db::Database src(o->src, {.create = false, .read_only = true});
      src.Backup(o->dest);
      const db::Database copy(o->dest, {.create = false, .read_only = true});
      const std::string check = copy.IntegrityCheck();
      if (check != "ok")
        throw std::runtime_error(o->dest + ": the copy fails SQLite's integrity check: " + check);
      fmt::print("{} -> {}: backup complete (schema v{}, integrity ok)\n", o->src, o->dest,
                 copy.SchemaVersion());
      return kExitOk;
    });
  });
}

}  // namespace hapticlab::cli
