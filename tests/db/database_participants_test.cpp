#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::database_participants_test {
namespace {

TEST(Database, ParticipantCodesMustBePseudonymous) {
  EXPECT_TRUE(IsPseudonymousCode("P07"));
  EXPECT_TRUE(IsPseudonymousCode("lab2-s_14"));
  EXPECT_FALSE(IsPseudonymousCode("Alice"));
  EXPECT_FALSE(IsPseudonymousCode("Alice Smith 1"));
  EXPECT_FALSE(IsPseudonymousCode(""));
  // Whatever a protocol's pattern admits (issue #34): no name, date, phone or e-mail shape.
  for (const char* ok : {"AB123", "SIM01", "lab2-014", "S-7", "X9999"})
    EXPECT_TRUE(IsPseudonymousCode(ok)) << ok;
  for (const char* bad :
       {"Anna_Kowalski_19850312", "JohnSmith1985", "1985-03-12", "015123456789", "0151-2345-678",
        "12_03", "P1-2", "Anna7", "a@b1", "p.07", "P123456", "ABCD1"})
    EXPECT_FALSE(IsPseudonymousCode(bad)) << bad;
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto study = db.CreateStudy({.name = "s", .protocol_toml = "x", .seed = 1});
  EXPECT_THROW(db.AddParticipant({.study_id = study, .code = "Alice"}), InputError);
  EXPECT_NO_THROW(db.AddParticipant({.study_id = study, .code = "P01"}));
}

// db::WriteTransaction (the runner's session start, `participant new`, a failed session's
// marker): what it writes is stored together or not at all, and it takes the write lock when
// made (BEGIN IMMEDIATE), so a second writer cannot slip in between its read and its write.
TEST(WriteTransaction, StoresAllOrNothing) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto study = db.CreateStudy({.name = "s", .protocol_toml = "x", .seed = 1});
  Database reader(dir.File("a.db"));
  try {
    WriteTransaction tx(db);
    db.AddParticipant({.study_id = study, .code = "P01"});
    EXPECT_TRUE(reader.Participants(study).empty());          // not visible before the commit
    db.AddParticipant({.study_id = study, .code = "Alice"});  // refused: throws
    tx.Commit();
    ADD_FAILURE() << "a name was accepted as a participant code";
  } catch (const InputError&) {
  }
  EXPECT_TRUE(db.Participants(study).empty());  // P01 rolled back with it
  {
    WriteTransaction tx(db);
    db.AddParticipant({.study_id = study, .code = "P01"});
    db.AddParticipant({.study_id = study, .code = "P02"});
    tx.Commit();
  }
  EXPECT_EQ(reader.Participants(study).size(), 2u);
  // The connection is free for the next one (and for methods keeping their own).
  WriteTransaction again(db);
  again.Commit();
}

TEST(WriteTransaction, TakesTheWriteLockWhenMade) {
  test::TempDir dir;
  const std::string path = dir.File("a.db");
  Database db(path);
  Database other(path, {.busy_timeout_ms = 20});
  WriteTransaction tx(db);  // nothing written yet, but the lock is held
  try {
    WriteTransaction second(other);
    ADD_FAILURE() << "a second write transaction began while the first held the lock";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find("locked"), std::string::npos) << what;
    EXPECT_EQ(what.find("BEGIN"), std::string::npos) << what;  // no SQL reaches a user
  }
  tx.Commit();
  EXPECT_NO_THROW(WriteTransaction(other).Commit());
}

}  // namespace
}  // namespace hapticlab::db::database_participants_test
