// hapticlab study freeze / verify / bundle / import, study run --plan and analyze --plan
// (docs/replication.md). References we did not write: GNU coreutils' sha256sum checks the
// manifest and the plan hash, GNU tar lists and repacks the bundles.

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "hapticlab/db/database.hpp"
#include "hapticlab/replication/plan.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_study_plan_test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string Cli() { return HL_CLI_PATH; }
std::string Small() { return test::DataPath("protocols/small.toml"); }

// Freezes the small test protocol (no power analysis: quick) into dir/plan.
std::string Freeze(const test::TempDir& dir) {
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " study freeze " + Small() + " -o " + dir.File("plan") +
                                 " --no-power --rig-device sim",
                             &out),
            0)
      << out;
  return test::ReadFile(dir.File("plan/PLAN.sha256")).substr(0, 64);
}

std::vector<std::string> PlanFiles(const std::string& dir) {
  std::vector<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path().lexically_relative(dir).generic_string());
  std::sort(files.begin(), files.end());
  return files;
}

TEST(StudyPlanCli, FreezeWritesAPlanThatSha256sumChecks) {
  test::TempDir dir;
  const std::string hash = Freeze(dir);
  const auto files = PlanFiles(dir.File("plan"));
  for (const char* f : {"MANIFEST.sha256", "PLAN.sha256", "analysis-plan.toml",
                        "protocol.canonical.json", "rig-template.toml", "protocol/small.toml",
                        "protocol/profiles.toml", "models/Denim.toml", "models/Towel.toml"})
    EXPECT_TRUE(std::count(files.begin(), files.end(), f)) << f;
  // coreutils: every file against the manifest, and the plan hash of the manifest.
  std::string out;
  EXPECT_EQ(
      test::RunCommand("cd " + dir.File("plan") + " && sha256sum --quiet -c MANIFEST.sha256 " +
                           "&& sha256sum --quiet -c PLAN.sha256",
                       &out),
      0)
      << out;
  EXPECT_EQ(test::RunCommand("sha256sum " + dir.File("plan/MANIFEST.sha256"), &out), 0);
  EXPECT_EQ(out.substr(0, 64), hash);
  // The canonical form's hash is the protocol identity a study database records.
  EXPECT_EQ(test::RunCommand("sha256sum " + dir.File("plan/protocol.canonical.json"), &out), 0);
  EXPECT_NE(test::ReadFile(dir.File("plan/analysis-plan.toml")).find(out.substr(0, 64)),
            std::string::npos);
  ASSERT_EQ(test::RunCommand(Cli() + " study verify " + dir.File("plan"), &out), 0) << out;
  EXPECT_NE(out.find(hash), std::string::npos) << out;
  // Freezing again gives the same plan (no time stamps).
  test::TempDir again;
  EXPECT_EQ(Freeze(again), hash);
  // The rig template reads as a rig file.
  EXPECT_EQ(test::RunCommand(Cli() + " rig show " + dir.File("plan/rig-template.toml"), &out), 0)
      << out;
}

// The power analysis runs on the plan's copy of the protocol and names its observer by the
// plan's copy of the observer file (tiny sizes: one pool participant, four simulations).
TEST(StudyPlanCli, FreezeRunsThePowerAnalysisWithItsObserver) {
  test::TempDir dir;
  fs::create_directories(dir.File("p"));
  fs::copy_file(test::DataPath("protocols/profiles.toml"), dir.File("p/profiles.toml"));
  fs::copy_file(std::string(HL_SOURCE_DIR) + "/studies/shin2019/observer.toml",
                dir.File("p/observer.toml"));
  std::string proto = test::ReadFile(Small());
  proto.replace(proto.find("profiles = "), 0, "observer = \"observer.toml\"\n");
  test::WriteFile(dir.File("p/small.toml"), proto);
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " study freeze " + dir.File("p/small.toml") + " -o " +
                                 dir.File("plan/") + " --power-pool 1 --power-simulations 4 " +
                                 "--power-participants 2,3 --quiet",
                             &out),
            0)
      << out;
  const auto power = json::parse(test::ReadFile(dir.File("plan/power.json")));
  EXPECT_EQ(power["observer"]["file"], "protocol/observer.toml") << power.dump();
  const std::string observer_sha = db::HashText(test::ReadFile(dir.File("p/observer.toml")));
  EXPECT_EQ(power["observer"]["sha256"], observer_sha);
  const std::string plan = test::ReadFile(dir.File("plan/analysis-plan.toml"));
  EXPECT_NE(plan.find("observer = \"protocol/observer.toml\""), std::string::npos) << plan;
  EXPECT_NE(plan.find("observer_sha256 = \"" + observer_sha + "\""), std::string::npos) << plan;
  EXPECT_NE(plan.find("primary_criterion = \"overall\""), std::string::npos) << plan;
  EXPECT_EQ(test::RunCommand(Cli() + " study verify " + dir.File("plan"), &out), 0) << out;
  // A protocol naming a file outside its folder cannot be frozen into a self-contained plan.
  std::string outside = test::ReadFile(Small());
  outside.replace(outside.find("profiles.toml"), 13, "../p/profiles.toml");
  fs::create_directories(dir.File("q"));
  test::WriteFile(dir.File("q/small.toml"), outside);
  EXPECT_EQ(test::RunCommand(Cli() + " study freeze " + dir.File("q/small.toml") + " -o " +
                                 dir.File("plan2") + " --no-power",
                             &out),
            2)
      << out;
  EXPECT_NE(out.find("study.profiles"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir.File("plan2")));
}

TEST(StudyPlanCli, VerifyNamesAOneByteChangeInEveryFile) {
  test::TempDir dir;
  Freeze(dir);
  const std::string plan = dir.File("plan");
  const auto files = PlanFiles(plan);
  ASSERT_GE(files.size(), 10u);
  for (const auto& f : files) {
    const std::string path = plan + "/" + f;
    const std::string original = test::ReadFile(path);
    for (const std::size_t at : {std::size_t{0}, original.size() / 2, original.size() - 1}) {
      std::string changed = original;
      changed[at] = static_cast<char>(changed[at] ^ 0x01);
      test::WriteFile(path, changed);
      const auto v = replication::VerifyPlan(plan);
      bool named = false;
      for (const auto& p : v.problems)
        named = named || p.path == f || p.detail.find(f) != std::string::npos;
      EXPECT_TRUE(named) << f << " byte " << at << ":\n" << v.Describe();
      test::WriteFile(path, original);
    }
  }
  EXPECT_TRUE(replication::VerifyPlan(plan).ok());
  // The command: a changed, a missing and an extra file, each named; exit 2.
  test::WriteFile(plan + "/protocol/small.toml", test::ReadFile(Small()) + " ");
  fs::remove(plan + "/models/Cork.toml");
  test::WriteFile(plan + "/notes.txt", "x");
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " study verify " + plan, &out), 2) << out;
  for (const char* s :
       {"changed: protocol/small.toml", "missing: models/Cork.toml", "extra: notes.txt"})
    EXPECT_NE(out.find(s), std::string::npos) << s << "\n" << out;
}

TEST(StudyPlanCli, BundleRoundTripAndTamperedBundleRefused) {
  test::TempDir dir;
  const std::string hash = Freeze(dir);
  std::string out;
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " study bundle " + dir.File("plan") + " -o " + dir.File("a.hlbundle"), &out),
      0)
      << out;
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " study bundle " + dir.File("plan") + " -o " + dir.File("b.hlbundle"), &out),
      0);
  EXPECT_EQ(test::ReadFile(dir.File("a.hlbundle")), test::ReadFile(dir.File("b.hlbundle")));
  // GNU tar reads it: every plan file, nothing else.
  ASSERT_EQ(test::RunCommand("tar -tzf " + dir.File("a.hlbundle") + " | sort", &out), 0) << out;
  std::string listed;
  for (const auto& f : PlanFiles(dir.File("plan"))) listed += f + "\n";
  EXPECT_EQ(out, listed);
  ASSERT_EQ(test::RunCommand(Cli() + " study import " + dir.File("a.hlbundle") +
                                 " --site S02 --device falcon -o " + dir.File("siteB"),
                             &out),
            0)
      << out;
  EXPECT_NE(out.find(hash), std::string::npos) << out;
  // The site code is checked as study run's --site: a lab's name is refused, nothing written.
  for (const char* name : {"LabB", "Berlin1"}) {
    EXPECT_EQ(test::RunCommand(Cli() + " study import " + dir.File("a.hlbundle") + " --site " +
                                   name + " -o " + dir.File("named"),
                               &out),
              2)
        << out;
    EXPECT_NE(out.find(std::string("'") + name + "' is not a site code"), std::string::npos) << out;
    EXPECT_FALSE(fs::exists(dir.File("named")));
  }
  EXPECT_EQ(test::RunCommand(Cli() + " study verify " + dir.File("siteB/plan"), &out), 0) << out;
  const std::string site = test::ReadFile(dir.File("siteB/site.toml"));
  EXPECT_NE(site.find("code = \"S02\""), std::string::npos) << site;
  EXPECT_NE(site.find(hash), std::string::npos) << site;
  const std::string rig = test::ReadFile(dir.File("siteB/rig.toml"));
  EXPECT_NE(rig.find("rig calibrate"), std::string::npos);
  EXPECT_EQ(test::RunCommand(Cli() + " rig show " + dir.File("siteB/rig.toml"), &out), 0) << out;

  // Tampered: one byte of the protocol changed, repacked with GNU tar; refused naming it.
  ASSERT_EQ(test::RunCommand("mkdir " + dir.File("x") + " && tar -xzf " + dir.File("a.hlbundle") +
                                 " -C " + dir.File("x") + " && sed -i 's/seed = 42/seed = 43/' " +
                                 dir.File("x/protocol/small.toml") + " && tar -czf " +
                                 dir.File("t.hlbundle") + " -C " + dir.File("x") + " .",
                             &out),
            0)
      << out;
  EXPECT_EQ(test::RunCommand(Cli() + " study import " + dir.File("t.hlbundle") + " --site S03 -o " +
                                 dir.File("siteC"),
                             &out),
            2)
      << out;
  EXPECT_NE(out.find("protocol/small.toml"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir.File("siteC/site.toml")));
  // Not a bundle at all; a bundle entry that leaves the directory.
  test::WriteFile(dir.File("junk.hlbundle"), "not a tar");
  EXPECT_EQ(test::RunCommand(Cli() + " study import " + dir.File("junk.hlbundle") +
                                 " --site S03 -o " + dir.File("siteC"),
                             &out),
            2)
      << out;
  ASSERT_EQ(test::RunCommand("cd " + dir.File("x") + " && tar -czf " + dir.File("u.hlbundle") +
                                 " --absolute-names ../x/PLAN.sha256",
                             &out),
            0)
      << out;
  EXPECT_EQ(test::RunCommand(Cli() + " study import " + dir.File("u.hlbundle") + " --site S03 -o " +
                                 dir.File("siteC"),
                             &out),
            2)
      << out;
  EXPECT_NE(out.find("unsafe path"), std::string::npos) << out;
}

// Lab A runs the plan as frozen; lab B imports the bundle, substitutes Denim's model and
// changes a protocol key: its report lists both as deviations, lab A's lists none.
TEST(StudyPlanCli, RunWithPlanRecordsTheHashAndAnalyzeListsDeviations) {
  test::TempDir dir;
  const std::string hash = Freeze(dir);
  std::string out;
  const std::string a_db = dir.File("a.db");
  ASSERT_EQ(test::RunCommand(Cli() + " study run --plan " + dir.File("plan") + " --db " + a_db +
                                 " --participant P01 --quiet",
                             &out),
            0)
      << out;
  {
    const db::Database d = db::OpenForReading(a_db);
    const auto st = d.Studies().at(0);
    const auto se = d.Sessions(d.Participants(st.id).at(0).id).at(0);
    const auto prov = json::parse(se.provenance_json);
    EXPECT_EQ(prov["plan_sha256"], hash);
    // The material_model table holds every model the session used, with the provenance's
    // hashes, which are the plan's (computed by freeze from the protocol independently).
    const std::string plan_text = test::ReadFile(dir.File("plan/analysis-plan.toml"));
    std::size_t models = 0;
    for (const auto& [id, h] : prov["model_hashes"].items()) {
      ++models;
      EXPECT_EQ(db::HashText(test::ReadFile(dir.File("plan/models/" + id + ".toml"))), h) << id;
      EXPECT_NE(plan_text.find(h.get<std::string>()), std::string::npos) << id;
    }
    EXPECT_EQ(models, 4u);
    // The table read by the sqlite3 shell: one row per material, its text hashing to its hash.
    std::string rows;
    ASSERT_EQ(
        test::RunCommand(
            "sqlite3 " + a_db + " \"SELECT name, hash FROM material_model ORDER BY name\"", &rows),
        0)
        << rows;
    std::string expected;
    for (const char* id : {"Acryl", "Cork", "Denim", "Towel"})
      expected += std::string(id) + "|" + prov["model_hashes"][id].get<std::string>() + "\n";
    EXPECT_EQ(rows, expected);
  }
  ASSERT_EQ(test::RunCommand(Cli() + " analyze --db " + a_db + " --out " + dir.File("ra") +
                                 " --no-figures --plan " + dir.File("plan"),
                             &out),
            0)
      << out;
  const std::string ra = test::ReadFile(dir.File("ra/report.md"));
  EXPECT_NE(ra.find("Deviations from the plan"), std::string::npos) << ra;
  EXPECT_NE(ra.find("None: the study ran and is analysed as planned"), std::string::npos) << ra;

  // Lab B.
  ASSERT_EQ(test::RunCommand(Cli() + " study bundle " + dir.File("plan") + " -o " +
                                 dir.File("s.hlbundle") + " && " + Cli() + " study import " +
                                 dir.File("s.hlbundle") + " --site S02 -o " + dir.File("b") +
                                 " --substitute Denim=" + dir.File("plan/models/Cork.toml"),
                             &out),
            0)
      << out;
  fs::create_directories(dir.File("changed"));
  // Lab B's Towel sample has more friction: its placeholder model (built from the profile)
  // differs from the plan's although no protocol key changed.
  std::string profiles = test::ReadFile(dir.File("b/plan/protocol/profiles.toml"));
  ASSERT_NE(profiles.find("mu_k = 0.7\n"), std::string::npos);
  profiles.replace(profiles.find("mu_k = 0.7\n"), 10, "mu_k = 0.8");
  test::WriteFile(dir.File("changed/profiles.toml"), profiles);
  std::string proto = test::ReadFile(dir.File("b/plan/protocol/small.toml"));
  const std::string from = "repetitions = 2";
  ASSERT_NE(proto.find(from), std::string::npos);
  proto.replace(proto.find(from), from.size(), "repetitions = 1");
  // ... and adds an analysis the plan does not name (the default list plus lmm).
  proto +=
      "\n[analysis]\ntests = [\"rm-anova\", \"tukey\", \"kruskal\", \"grouping\", "
      "\"aggregate\", \"correlation\", \"shapiro\", \"lmm\"]\n";
  test::WriteFile(dir.File("changed/small.toml"), proto);
  const std::string b_db = dir.File("b.db");
  ASSERT_EQ(test::RunCommand(Cli() + " study run " + dir.File("changed/small.toml") + " --plan " +
                                 dir.File("b") + " --db " + b_db + " --participant P01 --quiet",
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("deviation: protocol key changed from the plan: phase[2].repetitions: 2 -> 1"),
            std::string::npos)
      << out;
  // The session is the imported site's (no --site given); --site given wins, the provenance
  // keeps the site directory's code.
  const auto site_of = [](const std::string& path) {
    const db::Database d = db::OpenForReading(path);
    const auto se = d.Sessions(d.Participants(d.Studies().at(0).id).at(0).id).at(0);
    return std::make_pair(se.site_code, json::parse(se.provenance_json).value("plan_site", ""));
  };
  EXPECT_EQ(site_of(b_db), std::make_pair(std::string("S02"), std::string("S02")));
  EXPECT_EQ(
      test::RunCommand(Cli() + " study run --plan " + dir.File("b") + " --db " + dir.File("b9.db") +
                           " --participant P01 --site S09 --quiet " + "--stop-after 1",
                       &out),
      3)
      << out;
  EXPECT_EQ(site_of(dir.File("b9.db")), std::make_pair(std::string("S09"), std::string("S02")));
  ASSERT_EQ(test::RunCommand(Cli() + " analyze --db " + b_db + " --out " + dir.File("rb") +
                                 " --no-figures --correction HF --plan " + dir.File("b"),
                             &out),
            0)
      << out;
  const std::string rb = test::ReadFile(dir.File("rb/report.md"));
  EXPECT_NE(rb.find("| protocol key changed | phase[2].repetitions: 2 -> 1 |"), std::string::npos)
      << rb;
  EXPECT_NE(rb.find("| material substituted | Denim: the site's own model"), std::string::npos)
      << rb;
  EXPECT_NE(rb.find("at site S02"), std::string::npos) << rb;
  EXPECT_NE(rb.find("| model hash differs | Towel: model sha256 "), std::string::npos) << rb;
  EXPECT_EQ(rb.find("| model hash differs | Denim"), std::string::npos) << rb;  // substituted
  EXPECT_NE(rb.find("| analysis not in the plan | lmm (exploratory) |"), std::string::npos) << rb;
  EXPECT_NE(rb.find("read their results as exploratory): lmm\n"), std::string::npos) << rb;
  EXPECT_NE(rb.find("| correction changed | sphericity correction HF, the plan's GG |"),
            std::string::npos)
      << rb;
  // A site model changed after the import is refused before anything runs.
  test::WriteFile(dir.File("b/site-models/Denim.toml"),
                  test::ReadFile(dir.File("b/site-models/Denim.toml")) + "\n");
  EXPECT_EQ(test::RunCommand(Cli() + " study run --plan " + dir.File("b") + " --db " + b_db +
                                 " --participant P02 --quiet",
                             &out),
            2)
      << out;
  EXPECT_NE(out.find("Denim.toml"), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab::cmd_study_plan_test
