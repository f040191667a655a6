// The RAII helpers over SQLite's C API (db/src/sqlite_util.cpp): binds and reads of every
// type, a transaction rolled back unless committed, and errors that name the file and say
// in plain words what an SQLite result code means.

#include "../../db/src/sqlite_util.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::internal::sqlite_util_test {
namespace {

struct Connection {
  explicit Connection(const std::string& path) {
    if (sqlite3_open(path.c_str(), &db) != SQLITE_OK) throw std::runtime_error("open " + path);
  }
  ~Connection() { sqlite3_close(db); }
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;
  sqlite3* db = nullptr;
};

std::string Message(const auto& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(nothing thrown)";
}

TEST(SqliteUtil, BindsAndReadsEveryTypeExactly) {
  test::TempDir dir;
  Connection c(dir.File("u.db"));
  ExecSql(c.db, "CREATE TABLE t (i INTEGER, r REAL, s TEXT, b BLOB, n TEXT)");
  const std::int64_t big = std::numeric_limits<std::int64_t>::min() + 7;
  const std::string text("a\0b,\"c\"", 7);  // an embedded NUL survives
  const unsigned char blob[] = {0, 1, 2, 255};
  Stmt ins(c.db, "INSERT INTO t VALUES (?, ?, ?, ?, ?)");
  ins.Bind(1, big).Bind(2, 0.1).Bind(3, text).BindBlob(4, blob, sizeof blob).BindNull(5).Run();
  ins.Reset();  // clears the binds: all NULL
  ins.Run();
  Stmt q(c.db, "SELECT i, r, s, b, n FROM t ORDER BY rowid");
  ASSERT_TRUE(q.Step());
  EXPECT_EQ(q.Int(0), big);
  EXPECT_EQ(q.Real(1), 0.1);
  EXPECT_EQ(q.Text(2), text);
  ASSERT_EQ(q.BlobBytes(3), 4);
  EXPECT_EQ(std::memcmp(q.Blob(3), blob, 4), 0);
  EXPECT_TRUE(q.IsNull(4));
  EXPECT_TRUE(q.IsNumber(0));
  EXPECT_TRUE(q.IsNumber(1));
  EXPECT_FALSE(q.IsNumber(2));
  ASSERT_TRUE(q.Step());
  EXPECT_TRUE(q.IsNull(0));
  EXPECT_EQ(q.Text(2), "");
  EXPECT_FALSE(q.Step());
}

TEST(SqliteUtil, TransactionRollsBackUnlessCommitted) {
  test::TempDir dir;
  Connection c(dir.File("u.db"));
  ExecSql(c.db, "CREATE TABLE t (i INTEGER)");
  {
    Transaction tx(c.db);
    ExecSql(c.db, "INSERT INTO t VALUES (1)");
  }  // dropped: rolled back
  {
    Transaction tx(c.db);
    ExecSql(c.db, "INSERT INTO t VALUES (2)");
    tx.Commit();
  }
  Stmt q(c.db, "SELECT group_concat(i) FROM t");
  ASSERT_TRUE(q.Step());
  EXPECT_EQ(q.Text(0), "2");
}

TEST(SqliteUtil, ErrorsNameTheFileAndExplainTheCode) {
  test::TempDir dir;
  const std::string path = dir.File("u.db");
  Connection c(path);
  ExecSql(c.db, "CREATE TABLE t (i INTEGER UNIQUE)");
  const auto bad_sql = Message([&] { Stmt s(c.db, "SELEC nonsense"); });
  EXPECT_NE(bad_sql.find(path), std::string::npos) << bad_sql;
  // SQLite's reason, never the statement's text (users read these messages; issue #34).
  EXPECT_NE(bad_sql.find("syntax error"), std::string::npos) << bad_sql;
  EXPECT_EQ(bad_sql.find("SELEC nonsense"), std::string::npos) << bad_sql;
  const auto dup =
      Message([&] { ExecSql(c.db, "INSERT INTO t VALUES (1); INSERT INTO t VALUES (1)"); });
  EXPECT_NE(dup.find("UNIQUE"), std::string::npos) << dup;
  EXPECT_NE(dup.find(path), std::string::npos) << dup;
  Stmt ins(c.db, "INSERT INTO t VALUES (?)");
  ins.Bind(1, 1);
  const auto step = Message([&] { ins.Run(); });
  EXPECT_NE(step.find("step"), std::string::npos) << step;
  // A bind index out of range is SQLITE_RANGE.
  ins.Reset();
  EXPECT_THROW(ins.Bind(7, 1), std::runtime_error);

  // The plain explanations, extended codes included (SQLITE_IOERR_WRITE, SQLITE_BUSY_SNAPSHOT).
  EXPECT_NE(Explain(SQLITE_CORRUPT).find("damaged"), std::string::npos);
  EXPECT_NE(Explain(SQLITE_NOTADB).find("damaged"), std::string::npos);
  EXPECT_NE(Explain(SQLITE_FULL).find("disk is full"), std::string::npos);
  EXPECT_NE(Explain(SQLITE_IOERR_WRITE).find("I/O error"), std::string::npos);
  EXPECT_NE(Explain(SQLITE_BUSY_SNAPSHOT).find("locked"), std::string::npos);
  EXPECT_NE(Explain(SQLITE_READONLY).find("not writable"), std::string::npos);
  EXPECT_EQ(Explain(SQLITE_CONSTRAINT), "");

  // A file that is not a database: the explanation comes with SQLite's message.
  const std::string junk = dir.File("junk.db");
  test::WriteFile(junk, std::string(4096, 'j'));
  Connection j(junk);
  const auto notadb = Message([&] { ExecSql(j.db, "SELECT * FROM sqlite_master"); });
  EXPECT_NE(notadb.find("damaged or not a database"), std::string::npos) << notadb;
  EXPECT_NE(notadb.find(junk), std::string::npos) << notadb;
}

}  // namespace
}  // namespace hapticlab::db::internal::sqlite_util_test
