// db merge (db/merge.hpp): site-qualified participants, provenance kept, conflicts refused
// naming both inputs, byte-identical reruns, and no output after a SIGKILL mid-merge.

#include "hapticlab/db/merge.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <thread>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::merge_test {
namespace {

namespace fs = std::filesystem;

struct SiteSpec {
  std::string site;
  std::vector<std::string> codes;
  std::string plan = "p1";
  std::string protocol = "c1";
  int trials = 3;
  int chunk_samples = 64;  // per trial (float32 x 2 channels)
};

// A study database of one site: each participant with a session, trials, ratings that encode
// (site, participant, trial), an event, a trajectory chunk; one material model.
void MakeSite(const std::string& path, const SiteSpec& s) {
  Database db(path);
  const auto st = db.CreateStudy(
      {.name = "study", .protocol_toml = "x", .seed = 1, .protocol_canonical_sha256 = s.protocol});
  db.SaveMaterialModel("D", "[model]\nname = 'D'\n");
  for (std::size_t i = 0; i < s.codes.size(); ++i) {
    const auto pid = db.AddParticipant(
        {.study_id = st, .code = s.codes[i], .index = static_cast<int>(i), .seed = 7 + i});
    const auto se =
        db.StartSession({.participant_id = pid,
                         .software_version = "1.0+abc",
                         .provenance_json = R"({"plan_sha256":")" + s.plan +
                                            R"(","rig":{"file_sha256":"r)" + s.site + R"("}})",
                         .site_code = s.site});
    for (int t = 0; t < s.trials; ++t) {
      const auto id = db.AddTrial({.session_id = se,
                                   .plan_index = t,
                                   .phase = PhaseKind::kMain,
                                   .material = "D",
                                   .method = "m1"});
      db.StartTrial(id);
      TrajectoryChunk c{.trial_id = id, .stream = "force", .rate_hz = 1000, .channels = {"a", "b"}};
      for (int k = 0; k < 2 * s.chunk_samples; ++k) c.samples.push_back(static_cast<float>(k + t));
      c.attempt = 1;
      db.InsertTrajectoryChunk(c);
      db.CompleteTrial(id, {{"overall", 10.0 * static_cast<double>(i) + t, 1.5}});
      db.LogEvent({.session_id = se, .trial_id = id, .kind = EventKind::kBreak, .detail = s.site});
    }
    db.EndSession(se, SessionStatus::kCompleted);
  }
}

std::string Bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), {}};
}

// The message of the InputError MergeDatabases throws ("" when it does not throw).
std::string Refusal(const std::vector<std::string>& in, const std::string& out,
                    const MergeOptions& o = {}) {
  try {
    MergeDatabases(in, out, o);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Merge, ParticipantsGetSiteQualifiedCodesAndSessionsKeepTheirProvenance) {
  test::TempDir dir;
  const auto a = dir.File("a.db"), b = dir.File("b.db"), out = dir.File("all.db");
  MakeSite(a, {.site = "S1", .codes = {"P02", "P01"}});
  MakeSite(b, {.site = "S2", .codes = {"P03"}});
  const auto sum = MergeDatabases({b, a}, out);
  EXPECT_EQ(sum.sites, (std::vector<std::string>{"S1", "S2"}));
  EXPECT_EQ(sum.participants, 3);
  EXPECT_EQ(sum.sessions, 3);
  EXPECT_EQ(sum.ratings, 9);
  EXPECT_FALSE(fs::exists(out + ".merging"));
  EXPECT_FALSE(fs::exists(out + ".merging-build"));
  Database m(out, {.create = false, .read_only = true});
  EXPECT_EQ(m.IntegrityCheck(), "ok");
  const auto study = m.FindStudy("study");
  ASSERT_TRUE(study);
  const auto parts = m.Participants(study->id);
  ASSERT_EQ(parts.size(), 3u);
  // Each participant's ratings, trajectory and events are its own (ratings encode the index
  // of the participant at its site and the trial).
  const std::map<std::string, std::pair<std::string, int>> expected = {
      {"S1:P02", {"S1", 0}}, {"S1:P01", {"S1", 1}}, {"S2:P03", {"S2", 0}}};
  for (const auto& p : parts) {
    SCOPED_TRACE(p.code);
    ASSERT_TRUE(expected.count(p.code));
    const auto [site, idx] = expected.at(p.code);
    EXPECT_EQ(p.index, idx);
    const auto sessions = m.Sessions(p.id);
    ASSERT_EQ(sessions.size(), 1u);
    EXPECT_EQ(sessions[0].site_code, site);
    EXPECT_EQ(sessions[0].software_version, "1.0+abc");
    EXPECT_NE(sessions[0].provenance_json.find("\"file_sha256\":\"r" + site), std::string::npos);
    EXPECT_NE(sessions[0].provenance_json.find("\"plan_sha256\":\"p1\""), std::string::npos);
    const auto trials = m.Trials(sessions[0].id);
    ASSERT_EQ(trials.size(), 3u);
    for (const auto& t : trials) {
      const auto r = m.Ratings(t.id);
      ASSERT_EQ(r.size(), 1u);
      EXPECT_EQ(r[0].score, 10.0 * idx + t.plan_index);
      const auto chunks = m.TrajectoryChunks(t.id);
      ASSERT_EQ(chunks.size(), 1u);
      EXPECT_EQ(chunks[0].samples[1], static_cast<float>(1 + t.plan_index));
    }
    const auto events = m.Events(sessions[0].id);
    ASSERT_EQ(events.size(), 3u);
    for (const auto& e : events) {
      ASSERT_TRUE(e.trial_id);
      EXPECT_EQ(e.detail, site);
    }
  }
  // The model both sites stored is kept once.
  {
    sqlite3_stmt* s = nullptr;
    ASSERT_EQ(
        sqlite3_prepare_v2(m.handle(), "SELECT count(*) FROM material_model", -1, &s, nullptr),
        SQLITE_OK);
    ASSERT_EQ(sqlite3_step(s), SQLITE_ROW);
    EXPECT_EQ(sqlite3_column_int(s, 0), 1);
    sqlite3_finalize(s);
  }
}

TEST(Merge, TheSameInputsGiveTheSameBytesInAnyOrder) {
  test::TempDir dir;
  const auto a = dir.File("a.db"), b = dir.File("b.db");
  MakeSite(a, {.site = "S1", .codes = {"P01", "P02"}});
  MakeSite(b, {.site = "S2", .codes = {"P03"}});
  MergeDatabases({a, b}, dir.File("x.db"));
  MergeDatabases({b, a}, dir.File("y.db"));
  MergeDatabases({a, b}, dir.File("z.db"));
  const auto x = Bytes(dir.File("x.db"));
  ASSERT_GT(x.size(), 4096u);
  EXPECT_TRUE(x == Bytes(dir.File("y.db")));
  EXPECT_TRUE(x == Bytes(dir.File("z.db")));
  // A merged file merges again with a third site; its codes stay qualified once.
  const auto c = dir.File("c.db");
  MakeSite(c, {.site = "S3", .codes = {"P01"}});
  const auto sum =
      MergeDatabases({dir.File("x.db"), c}, dir.File("w.db"), {.allow_shared_codes = true});
  EXPECT_EQ(sum.participants, 4);
  Database w(dir.File("w.db"), {.create = false, .read_only = true});
  EXPECT_TRUE(w.FindParticipant(w.FindStudy("study")->id, "S3:P01"));
  EXPECT_TRUE(w.FindParticipant(w.FindStudy("study")->id, "S1:P01"));
}

TEST(Merge, ConflictsAreRefusedNamingBothInputsUnlessAllowed) {
  test::TempDir dir;
  const auto a = dir.File("a.db"), out = dir.File("out.db");
  MakeSite(a, {.site = "S1", .codes = {"P01"}});
  auto names_both = [](const std::string& msg, const std::string& x, const std::string& y) {
    return msg.find(x) != std::string::npos && msg.find(y) != std::string::npos;
  };
  // Itself: the same path, a hard link, a copy.
  auto msg = Refusal({a, a}, out);
  EXPECT_NE(msg.find("itself"), std::string::npos) << msg;
  const auto link = dir.File("link.db"), copy = dir.File("copy.db");
  fs::create_hard_link(a, link);
  EXPECT_TRUE(names_both(Refusal({a, link}, out), a, link));
  fs::copy_file(a, copy);
  msg = Refusal({a, copy}, out);
  EXPECT_TRUE(names_both(msg, a, copy)) << msg;
  EXPECT_NE(msg.find("S1:P01"), std::string::npos) << msg;
  // Different plans.
  const auto b = dir.File("b.db");
  MakeSite(b, {.site = "S2", .codes = {"P02"}, .plan = "p2"});
  msg = Refusal({a, b}, out);
  EXPECT_TRUE(names_both(msg, a, b)) << msg;
  EXPECT_NE(msg.find("different plans"), std::string::npos) << msg;
  // One code at two sites.
  const auto c = dir.File("c.db");
  MakeSite(c, {.site = "S3", .codes = {"P01"}});
  msg = Refusal({c, a}, out);
  EXPECT_TRUE(names_both(msg, a, c)) << msg;
  EXPECT_NE(msg.find("sites S1 and S3"), std::string::npos) << msg;
  // Different protocols.
  const auto d = dir.File("d.db");
  MakeSite(d, {.site = "S4", .codes = {"P04"}, .protocol = "c2"});
  EXPECT_TRUE(names_both(Refusal({a, d}, out), a, d));
  EXPECT_FALSE(fs::exists(out));
  // Allowed by name: merged.
  EXPECT_EQ(Refusal({a, b}, out, {.allow_different_plans = true}), "");
  EXPECT_EQ(Refusal({a, c}, dir.File("o2.db"), {.allow_shared_codes = true}), "");
  EXPECT_EQ(Refusal({a, d}, dir.File("o3.db"), {.allow_different_protocols = true}), "");
  // An existing output is never overwritten.
  const auto before = Bytes(out);
  EXPECT_NE(Refusal({a, b}, out, {.allow_different_plans = true}).find("already exists"),
            std::string::npos);
  EXPECT_TRUE(before == Bytes(out));
  EXPECT_NE(Refusal({a, b}, dir.File("none/o.db"), {.allow_different_plans = true})
                .find("folder does not exist"),
            std::string::npos);
}

// A file of schema v8 (before sites) is migrated forward: its sessions are the local site's.
TEST(Merge, AnOlderInputIsMigratedFirst) {
  test::TempDir dir;
  const auto old = dir.File("old.db"), b = dir.File("b.db");
  {
    Database db(old, {.migrate_to = 8});
    db.Exec(
        "INSERT INTO study(name, protocol_toml, protocol_hash, seed, "
        "protocol_canonical_sha256) VALUES ('study','x','h',1,'c1')");
    db.Exec("INSERT INTO participant(study_id, code, idx, seed) VALUES (1,'P09',0,11)");
    db.Exec(
        "INSERT INTO session(participant_id, provenance_json) VALUES "
        "(1, '{\"plan_sha256\":\"p1\"}')");
  }
  MakeSite(b, {.site = "S2", .codes = {"P01"}});
  const auto sum = MergeDatabases({old, b}, dir.File("o.db"));
  EXPECT_EQ(sum.sites, (std::vector<std::string>{kDefaultSiteCode, "S2"}));
  Database m(dir.File("o.db"), {.create = false, .read_only = true});
  EXPECT_EQ(m.SchemaVersion(), kSchemaVersion);
  EXPECT_TRUE(m.FindParticipant(m.FindStudy("study")->id, std::string(kDefaultSiteCode) + ":P09"));
}

// SIGKILL at random moments of a merge: the output is either absent or whole (identical to a
// clean merge); a rerun after the kills gives the same bytes.
TEST(Merge, SigkillMidMergeLeavesNoPartialOutput) {
  test::TempDir dir;
  const auto a = dir.File("a.db"), b = dir.File("b.db"), ref = dir.File("ref.db"),
             out = dir.File("out.db");
  MakeSite(a, {.site = "S1", .codes = {"P01", "P02"}, .trials = 10, .chunk_samples = 16000});
  MakeSite(b, {.site = "S2", .codes = {"P03", "P04"}, .trials = 10, .chunk_samples = 16000});
  MergeDatabases({a, b}, ref);
  const auto expected = Bytes(ref);
  std::mt19937_64 rng(20261127);  // fixed seed: the kill moments are reproducible
  std::uniform_int_distribution<int> delay_us(0, 30000);
  int killed = 0;
  for (int round = 0; round < 5; ++round) {
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      try {
        MergeDatabases({a, b}, out);
      } catch (...) {
        _exit(3);
      }
      _exit(0);
    }
    std::this_thread::sleep_for(std::chrono::microseconds(delay_us(rng)));
    kill(pid, SIGKILL);
    int status = 0;
    waitpid(pid, &status, 0);
    if (WIFSIGNALED(status)) {
      ++killed;
    } else {
      ASSERT_EQ(WEXITSTATUS(status), 0);
    }
    if (fs::exists(out)) {
      EXPECT_TRUE(Bytes(out) == expected) << "round " << round << ": a partial output";
      fs::remove(out);
    }
  }
  MergeDatabases({a, b}, out);  // the rerun replaces what the killed merges left
  EXPECT_TRUE(Bytes(out) == expected);
  EXPECT_FALSE(fs::exists(out + ".merging"));
  RecordProperty("killed_rounds", killed);
  std::printf("merges killed mid-way: %d of 5\n", killed);
}

}  // namespace
}  // namespace hapticlab::db::merge_test
