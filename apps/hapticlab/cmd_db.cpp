// hapticlab db: copies of a study database that are safe while a session writes to it.

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/merge.hpp"

namespace hapticlab::cli {

namespace {

void RegisterDbMerge(CLI::App& group) {
  struct O {
    std::vector<std::string> inputs;
    std::string out;
    db::MergeOptions options;
  };
  auto o = std::make_shared<O>();
  auto* cmd = group.add_subcommand(
      "merge",
      "Combine the study databases of several rigs or sites into a new file: participants get\n"
      "site-qualified codes (S02:P07), every session keeps its provenance (site, rig hash, plan\n"
      "hash, software version). Refused (exit 2, naming both inputs): the same file twice, a\n"
      "participant in two inputs, a code used at two sites, different plans or protocols,\n"
      "unless the flags below allow them. Older inputs are migrated forward first. Atomic and\n"
      "deterministic: a killed merge leaves no OUTPUT; the same inputs give the same bytes\n"
      "(docs/replication.md, \"Combining sites\").");
  cmd->add_option("INPUTS", o->inputs, "Study databases (two or more)")->required();
  cmd->add_option("-o,--output", o->out, "New file for the merged database (never overwritten)")
      ->required();
  cmd->add_flag("--allow-shared-codes", o->options.allow_shared_codes,
                "Merge although one participant code is used at two sites");
  cmd->add_flag("--allow-different-plans", o->options.allow_different_plans,
                "Merge sessions recorded under different plans (provenance plan_sha256)");
  cmd->add_flag("--allow-different-protocols", o->options.allow_different_protocols,
                "Merge a study whose protocol differs between inputs");
  cmd->callback([o] {
    RunGuarded([&] {
      const auto s = db::MergeDatabases(o->inputs, o->out, o->options);
      fmt::print("{} databases -> {}: sites {}, {} participants, {} sessions, {} ratings\n",
                 o->inputs.size(), o->out, fmt::join(s.sites, ", "), s.participants, s.sessions,
                 s.ratings);
      if (s.reserved_left_out)
        fmt::print("{} reserved participant codes without a session were not carried over\n",
                   s.reserved_left_out);
      return kExitOk;
    });
  });
}

}  // namespace

void RegisterDb(CLI::App& app) {
  auto* group = app.add_subcommand(
      "db", "Study database files: an online backup, merging sites (docs/studies.md)");
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
    RunGuarded({{"db", "SRC"}}, [&] {  // the database layer names its file "db"
      std::error_code ec;              // a path that cannot be looked up is not there
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
  RegisterDbMerge(*group);
}

}  // namespace hapticlab::cli
