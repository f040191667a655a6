// hapticlab participant new through the command line (apps/hapticlab/cmd_participant.cpp): the
// lowest free code of the protocol's study that its participant_code pattern accepts, reserved
// in the database. (Codes
// refused by `study run`: FaultCli.ParticipantCodesByConstructionAndNothingWrittenForARefusedOne.)

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_participant_test {
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

TEST(ParticipantCli, NewReservesTheLowestFreeCodeOfTheStudy) {
  test::TempDir dir;
  const std::string db = dir.File("s.db");
  // No database yet: created, with the study and the code reserved in it.
  EXPECT_EQ(NewCode(Small(), db, ""), "P01\n");
  EXPECT_EQ(NewCode(Small(), db, ""), "P02\n");  // the first is taken now
  {
    db::Database d(db);
    const auto st = d.FindStudy("test-small");
    ASSERT_TRUE(st);
    const auto parts = d.Participants(st->id);
    ASSERT_EQ(parts.size(), 2u);
    EXPECT_TRUE(d.IsReserved(parts[0].id));
    d.AddParticipant({.study_id = st->id, .code = "P04", .index = 2});
    // Another study's codes are not this study's.
    const auto other = d.CreateStudy({.name = "other", .protocol_toml = "x", .seed = 1});
    d.AddParticipant({.study_id = other, .code = "P03"});
  }
  EXPECT_EQ(NewCode(Small(), db, ""), "P03\n");  // the gap, not after the largest
  EXPECT_EQ(NewCode(Small(), db, " --prefix AB"), "AB01\n");
  std::string status;
  ASSERT_EQ(test::RunCommand(Cli() + " study status --db " + db, &status), 0) << status;
  EXPECT_NE(status.find("reserved"), std::string::npos) << status;
  // A prefix the pattern (^[A-Z]{1,3}[0-9]{2,4}$) never accepts: exit 2 naming the option.
  const std::string out = NewCode(Small(), db, " --prefix p", 2);
  EXPECT_NE(out.find("--prefix: no code 'p' followed by a number"), std::string::npos) << out;
  // A missing protocol is bad input.
  EXPECT_EQ(test::RunCommand(Cli() + " participant new --protocol " + dir.File("none.toml") +
                             " --db " + db),
            2);
}

TEST(ParticipantCli, NewInfersThePrefixOfTheProtocolsOwnPattern) {
  test::TempDir dir;
  std::filesystem::copy_file(test::DataPath("protocols/profiles.toml"), dir.File("profiles.toml"));
  std::string text = test::ReadFile(Small());
  text.replace(text.find("seed = 42"), 9, "seed = 42\nparticipant_code = \"^NU[0-9]{3}$\"");
  test::WriteFile(dir.File("p.toml"), text);
  // Two consoles (processes) at once never get the same code.
  std::string both;
  ASSERT_EQ(test::RunCommand("(" + Cli() + " participant new --protocol " + dir.File("p.toml") +
                                 " --db " + dir.File("s.db") + " & " + Cli() +
                                 " participant new --protocol " + dir.File("p.toml") + " --db " +
                                 dir.File("s.db") + "; wait) | sort",
                             &both),
            0);
  EXPECT_EQ(both, "NU001\nNU002\n");
  // The protocol changed since the study was recorded: refused with the key and both values.
  text.replace(text.find("repetitions = 2"), 15, "repetitions = 4");
  test::WriteFile(dir.File("p.toml"), text);
  const std::string out = NewCode(dir.File("p.toml"), dir.File("s.db"), "", 2);
  EXPECT_NE(out.find("phase[2].repetitions: 2 -> 4"), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab::cmd_participant_test
