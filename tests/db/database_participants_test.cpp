#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db {
namespace {

TEST(Database, ParticipantCodesMustBePseudonymous) {
  EXPECT_TRUE(IsPseudonymousCode("P07"));
  EXPECT_TRUE(IsPseudonymousCode("lab2-s_14"));
  EXPECT_FALSE(IsPseudonymousCode("Alice"));
  EXPECT_FALSE(IsPseudonymousCode("Alice Smith 1"));
  EXPECT_FALSE(IsPseudonymousCode(""));
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto study = db.CreateStudy({.name = "s", .protocol_toml = "x", .seed = 1});
  EXPECT_THROW(db.AddParticipant({.study_id = study, .code = "Alice"}), InputError);
  EXPECT_NO_THROW(db.AddParticipant({.study_id = study, .code = "P01"}));
}

}  // namespace
}  // namespace hapticlab::db
