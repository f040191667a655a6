// db merge: one input's rows copied into the build file with new, deterministic ids.
//
// Plain SQL over an attached input (INSERT ... SELECT ... ORDER BY): SQLite copies blobs and
// values without a round trip through C++. New ids come from row_number() over the
// site-qualified participant code and the input's own row order, so they never depend on the
// order the inputs were named in or on the time of the merge.
#include <fmt/format.h>

#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "merge_internal.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db::internal {

namespace {

// How one table is copied: the expression of each column that is not the source row's own
// (`x.<column>`), the FROM clause (the source table is `x`) and the row order.
struct TableCopy {
  const char* table;
  std::map<std::string, std::string> columns;
  std::string from;
  std::string order;
  bool or_ignore = false;
};

// Columns of a table of the build file, in their order (names from our own schema).
std::vector<std::string> Columns(sqlite3* db, const std::string& table) {
  Stmt s(db, "SELECT name FROM pragma_table_info(?, 'main') ORDER BY cid");
  s.Bind(1, table);
  std::vector<std::string> out;
  while (s.Step()) out.push_back(s.Text(0));
  return out;
}

void Copy(sqlite3* db, const TableCopy& c) {
  std::string names, values;
  for (const auto& col : Columns(db, c.table)) {
    const auto it = c.columns.find(col);
    names += (names.empty() ? "" : ", ") + col;
    values += (values.empty() ? "" : ", ") + (it == c.columns.end() ? "x." + col : it->second);
  }
  ExecSql(db, fmt::format("INSERT {}INTO main.{}({}) SELECT {} FROM {} ORDER BY {}",
                          c.or_ignore ? "OR IGNORE " : "", c.table, names, values, c.from, c.order)
                  .c_str());
}

// New ids of a table's rows: the build's largest id plus the row's rank in `order`.
void MapIds(sqlite3* db, const std::string& map, const std::string& table,
            const std::string& select, const std::string& from, const std::string& order) {
  ExecSql(db, fmt::format("CREATE TEMP TABLE {} AS SELECT {}, (SELECT coalesce(max(id), 0) FROM "
                          "main.{}) + row_number() OVER (ORDER BY {}) AS dst FROM {}",
                          map, select, table, order, from)
                  .c_str());
}

// Every table of the schema and whether the merge copies it; a table added to the schema
// without a rule here stops the merge (and the test of a fresh file) instead of being lost.
const std::set<std::string> kKnownTables = {
    "schema_version", "study",       "participant",      "session",           "trial",
    "rating",         "event",       "trajectory_chunk", "trajectory_stream", "side_timing",
    "material_model", "writer_lease"};  // the lease is the writing process's, never merged

void CheckKnownTables(sqlite3* db) {
  Stmt t(db,
         "SELECT name FROM main.sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'");
  while (t.Step())
    if (!kKnownTables.count(t.Text(0)))
      throw std::logic_error("db merge has no rule for table '" + t.Text(0) +
                             "' (db/src/merge_copy.cpp)");
}

void CopyRows(sqlite3* db, bool first) {
  for (const char* m : {"m_study", "m_participant", "m_session", "m_trial"})
    ExecSql(db, fmt::format("DROP TABLE IF EXISTS temp.{}", m).c_str());
  if (first) {
    ExecSql(db, "DELETE FROM main.schema_version");
    ExecSql(db,
            "INSERT INTO main.schema_version SELECT * FROM src.schema_version ORDER BY version");
  }
  Copy(db, {"study",
            {{"id", "NULL"}},
            "src.study x WHERE x.name NOT IN (SELECT name FROM main.study)",
            "x.name"});
  ExecSql(db,
          "CREATE TEMP TABLE m_study AS SELECT x.id AS src, y.id AS dst FROM src.study x JOIN "
          "main.study y ON y.name = x.name");
  // Participants with a session, by site-qualified code ("SITE:CODE"; kept when qualified).
  MapIds(db, "m_participant", "participant", "src, study_dst, code",
         "(SELECT p.id AS src, ms.dst AS study_dst, CASE WHEN instr(p.code, ':') > 0 THEN p.code "
         "ELSE ss.site || ':' || p.code END AS code FROM src.participant p JOIN temp.m_study ms "
         "ON ms.src = p.study_id JOIN (SELECT participant_id, min(site_code) AS site FROM "
         "src.session GROUP BY participant_id) ss ON ss.participant_id = p.id)",
         "study_dst, code");
  Copy(db, {"participant",
            {{"id", "m.dst"}, {"study_id", "m.study_dst"}, {"code", "m.code"}},
            "src.participant x JOIN temp.m_participant m ON m.src = x.id",
            "m.dst"});
  MapIds(db, "m_session", "session", "x.id AS src",
         "src.session x JOIN temp.m_participant mp ON mp.src = x.participant_id", "mp.dst, x.id");
  Copy(db, {"session",
            {{"id", "m.dst"}, {"participant_id", "mp.dst"}},
            "src.session x JOIN temp.m_session m ON m.src = x.id JOIN temp.m_participant mp ON "
            "mp.src = x.participant_id",
            "m.dst"});
  MapIds(db, "m_trial", "trial", "x.id AS src",
         "src.trial x JOIN temp.m_session ms ON ms.src = x.session_id", "ms.dst, x.id");
  Copy(db, {"trial",
            {{"id", "m.dst"}, {"session_id", "ms.dst"}},
            "src.trial x JOIN temp.m_trial m ON m.src = x.id JOIN temp.m_session ms ON ms.src = "
            "x.session_id",
            "m.dst"});
  for (const char* t : {"rating", "trajectory_chunk", "trajectory_stream", "side_timing"})
    Copy(db, {t,
              {{"id", "NULL"}, {"trial_id", "mt.dst"}},
              fmt::format("src.{} x JOIN temp.m_trial mt ON mt.src = x.trial_id", t),
              "mt.dst, x.id"});
  Copy(db, {"event",
            {{"id", "NULL"}, {"session_id", "ms.dst"}, {"trial_id", "mt.dst"}},
            "src.event x JOIN temp.m_session ms ON ms.src = x.session_id LEFT JOIN temp.m_trial mt "
            "ON mt.src = x.trial_id",
            "ms.dst, x.id"});
  Copy(db, {"material_model",
            {{"id", "NULL"}},
            "src.material_model x",
            "x.name, x.hash",
            /*or_ignore=*/true});
}

}  // namespace

void CopyInput(sqlite3* build, const std::string& input_path, bool first) {
  CheckKnownTables(build);
  {
    Stmt attach(build, "ATTACH DATABASE ? AS src");
    attach.Bind(1, input_path).Run();
  }
  try {
    Transaction tx(build);
    CopyRows(build, first);
    tx.Commit();
  } catch (...) {
    ExecSql(build, "DETACH DATABASE src");
    throw;
  }
  ExecSql(build, "DETACH DATABASE src");
}

MergeSummary Summarize(sqlite3* merged) {
  MergeSummary sum;
  Stmt sites(merged, "SELECT DISTINCT site_code FROM session ORDER BY site_code");
  while (sites.Step()) sum.sites.push_back(sites.Text(0));
  Stmt n(merged,
         "SELECT (SELECT count(*) FROM participant), (SELECT count(*) FROM session), "
         "(SELECT count(*) FROM rating)");
  n.Step();
  sum.participants = static_cast<int>(n.Int(0));
  sum.sessions = static_cast<int>(n.Int(1));
  sum.ratings = static_cast<int>(n.Int(2));
  return sum;
}

}  // namespace hapticlab::db::internal
