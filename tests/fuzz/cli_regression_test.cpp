// The findings of issue #34's fuzzing, replayed through the command line (cli_child.hpp):
// corpus/regression/<reader>__<what>.* and generated inputs too large to keep as files. Each
// must end as stated (exit 0 or 2, never a signal, a timeout, exit 1, library text or SQL).

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cli_child.hpp"
#include "cli_pool.hpp"
#include "hapticlab/test/sqlite_peek.hpp"
#include "hapticlab/test/test_util.hpp"
#include "seeds.hpp"

namespace hapticlab::fuzz::cli_regression_test {
namespace {

// One finding: its files are written by `setup` into the slot folder, then `job` runs.
struct Case {
  std::string name;
  std::function<Job(const std::string& slot)> job;
};

void Replay(const std::vector<Case>& cases) {
  test::TempDir dir;
  Pool pool(1, CliLimits(20), dir.path());
  for (const auto& c : cases) {
    const auto findings = pool.Run(
        1, [&](int, const std::string& slot) { return c.job(slot); }, c.name, "");
    EXPECT_TRUE(findings.empty()) << findings.front();
  }
}

std::string Regression(const std::string& name) {
  return test::ReadFile(CorpusPath("regression/" + name));
}

// Writes `text` as `name` in `slot`; returns its path.
std::string Put(const std::string& slot, const std::string& name, const std::string& text) {
  test::WriteFile(slot + "/" + name, text);
  return slot + "/" + name;
}

std::vector<std::string> Photometric(const std::string& slot, const std::string& lights) {
  return {"model", "photometric", "--images", slot, "--lights",
          lights,  "--pitch-m",   "1e-4",     "-o", slot + "/h.f32"};
}

TEST(CliRegression, PhotometricInputs) {
  Replay({
      {"lights file of one NUL byte (SIGSEGV)",
       [](const std::string& s) {
         WriteImages(s);
         return Job{.args = Photometric(s, Put(s, "l.txt", Regression("lights__nul_byte.txt"))),
                    .allowed = {2}};
       }},
      {"20030 lights (456 s)",
       [](const std::string& s) {
         WriteImages(s);
         return Job{.args = Photometric(s, Put(s, "l.txt", LightsFile(20030))), .allowed = {2}};
       }},
      {"594-byte TGA claiming 65535 x 65535 pixels (17 GB)",
       [](const std::string& s) {
         WriteImages(s);
         WriteLights(s);
         Put(s, "i0.tga", Regression("image__tga_65535x65535.tga"));
         return Job{.args = Photometric(s, s + "/lights.txt"), .allowed = {2}};
       }},
  });
}

TEST(CliRegression, Protocols) {
  auto validate = [](const std::string& file, const std::vector<int>& allowed) {
    return [=](const std::string& s) {
      WriteStudyFiles(s);
      return Job{.args = {"study", "validate", Put(s, "p.toml", Regression(file))},
                 .allowed = allowed};
    };
  };
  auto run = [](const std::string& file, const std::string& code) {
    return [=](const std::string& s) {
      WriteStudyFiles(s);
      return Job{.args = {"study", "run", Put(s, "p.toml", Regression(file)), "--db", s + "/s.db",
                          "--participant", code, "--device", "sim", "--quiet"},
                 .allowed = {2},
                 .not_in_output = {"completed"}};
    };
  };
  Replay({
      {"1000 materials (73 s)", validate("protocol__1000_materials.toml", {0})},
      {"100000 materials (hang)",
       [](const std::string& s) {
         WriteStudyFiles(s);
         return Job{.args = {"study", "validate", Put(s, "p.toml", ProtocolWithMaterials(100000))},
                    .allowed = {2}};
       }},
      {"masking_noise.level_dB = inf", validate("protocol__masking_level_inf.toml", {2})},
      {"a break of 1e300 s", validate("protocol__break_1e300_s.toml", {2})},
      {"^(A|A)*B$ on a 32-letter code (437 s)",
       run("protocol__code_pattern_backtracking.toml", "AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAC")},
      {"a pattern admitting a name and birth date",
       run("protocol__pattern_admits_names.toml", "Anna_Kowalski_19850312")},
      {"a pattern admitting a date", run("protocol__pattern_admits_names.toml", "1985-03-12")},
  });
}

TEST(CliRegression, RigMaterialAndRecordings) {
  Replay({
      {"tip_offset_m 1e18",
       [](const std::string& s) {
         return Job{
             .args = {"rig", "show", Put(s, "r.toml", Regression("rig__tip_offset_1e18.toml"))},
             .allowed = {2}};
       }},
      {"mu_b 1e100",
       [](const std::string& s) {
         return Job{
             .args = {"model", "check", Put(s, "m.toml", Regression("material__mu_b_1e100.toml"))},
             .allowed = {2}};
       }},
      {"fit-vibration --rate 1e-6 (soxr loops)",
       [](const std::string& s) {
         WriteRecordings(s);
         return Job{.args = {"model", "fit-vibration", "--recordings", s, "--rate", "1e-6", "-o",
                             s + "/bank.toml"},
                    .allowed = {2}};
       }},
  });
}

TEST(CliRegression, LargeCsvFilesStayWithinTheBound) {
  if (kSanitized) GTEST_SKIP() << "2e6-row files: release build only";
  Replay({
      {"a 2e6-row measurement CSV (925 MB)",
       [](const std::string& s) {
         return Job{.args = {"measurement", "check", Put(s, "d.csv", MeasurementRows(2'000'000))},
                    .allowed = {0}};
       }},
      {"a 2.1e6-row long-format CSV",
       [](const std::string& s) {
         return Job{.args = {"stats", "kruskal", "--csv", Put(s, "r.csv", RatingRows(2'100'000)),
                             "--dv", "score", "--group", "method"},
                    .allowed = {2}};
       }},
  });
}

// An SQLite file with the given statements applied to the seed study database.
std::string Tampered(const std::string& slot, const std::string& sql) {
  std::string path = Put(slot, "s.db", StudyDatabaseSeed(slot));
  test::ExecSql(path, sql);
  return path;
}

TEST(CliRegression, DatabasesThatAreNotStudyRecords) {
  auto status = [](const std::string& sql) {
    return [=](const std::string& s) {
      return Job{.args = {"study", "status", "--db", Tampered(s, sql), "--json"},
                 .allowed = {2},
                 .not_in_output = {"quick_check", "no such table"}};
    };
  };
  Replay({
      {"another program's SQLite file",
       [](const std::string& s) {
         test::ExecSql(s + "/other.db", "CREATE TABLE notes(id INTEGER, text TEXT)");
         return Job{.args = {"study", "status", "--db", s + "/other.db", "--json"}, .allowed = {2}};
       }},
      {"a table dropped", status("DROP TABLE rating")},
      {"a re-run migration (schema_version rolled back)",
       status("DELETE FROM schema_version WHERE version > 1")},
  });
}

}  // namespace
}  // namespace hapticlab::fuzz::cli_regression_test
