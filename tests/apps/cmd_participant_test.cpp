// hapticlab participant new through the command line (apps/hapticlab/cmd_participant.cpp): the
// lowest free code of the protocol's study that its participant_code pattern accepts. (Codes
// refused by `study run`: FaultCli.ParticipantCodesByConstructionAndNothingWrittenForARefusedOne.)

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab {
namespace {

std::string Cli() { return HL_CLI_PATH; }
std::string Small() { return test::DataPath("protocols/small.toml"); }

std::string NewCode(const std::string& protocol, const std::string& db, const std::string& extra,
                    int expected_rc = 0) {
  std::string out;
  EXPECT_EQ(test::RunCommand(
                Cli() + " participant new --protocol " + protocol + " --db " + db + extra, &out),
            expected_rc)
      << out;
  return out;
}

TEST(ParticipantCli, NewHandsOutTheLowestFreeCodeOfTheStudy) {
  test::TempDir dir;
  const std::string db = dir.File("s.db");
  // No database yet: the first code, and nothing written.
  EXPECT_EQ(NewCode(Small(), db, ""), "P01\n");
  EXPECT_FALSE(std::filesystem::exists(db));
  {
    db::Database d(db);
    const auto st = d.CreateStudy({.name = "test-small", .protocol_toml = "x", .seed = 1});
    for (const char* c : {"P01", "P02", "P04"}) d.AddParticipant({.study_id = st, .code = c});
    // Another study's codes are not this study's.
    const auto other = d.CreateStudy({.name = "other", .protocol_toml = "x", .seed = 1});
    d.AddParticipant({.study_id = other, .code = "P03"});
  }
  EXPECT_EQ(NewCode(Small(), db, ""), "P03\n");  // the gap, not after the largest
  EXPECT_EQ(NewCode(Small(), db, " --prefix AB"), "AB01\n");
  // A prefix the pattern (^[A-Z]{1,3}[0-9]{2,4}$) never accepts: exit 2 naming the protocol
  // and the option.
  const std::string out = NewCode(Small(), db, " --prefix p", 2);
  EXPECT_NE(out.find(Small() + ": --prefix: no free code 'pNN'"), std::string::npos) << out;
  // A missing database folder is bad input naming the option.
  EXPECT_EQ(test::RunCommand(Cli() + " participant new --protocol " + dir.File("none.toml") +
                             " --db " + db),
            2);
}

TEST(ParticipantCli, NewFollowsTheProtocolsOwnPattern) {
  test::TempDir dir;
  std::filesystem::copy_file(test::DataPath("protocols/profiles.toml"), dir.File("profiles.toml"));
  std::string text = test::ReadFile(Small());
  text.replace(text.find("seed = 42"), 9, "seed = 42\nparticipant_code = \"^S[0-9]{3}$\"");
  test::WriteFile(dir.File("p.toml"), text);
  // Two digits or more: S01 .. S99 do not match three digits, S100 is the first that does.
  EXPECT_EQ(NewCode(dir.File("p.toml"), dir.File("s.db"), " --prefix S"), "S100\n");
}

}  // namespace
}  // namespace hapticlab
