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

}  // namespace
}  // namespace hapticlab::db::database_participants_test
