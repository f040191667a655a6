// Fuzzing the command line: every reader of untrusted input gets its corpus
// (tests/fuzz/corpus/<reader>/) and a fixed number of mutants from a fixed seed, each run
// through `hapticlab` (cli::RunCli in a forked child, cli_child.hpp) as a user would run it.
// A finding is a signal, a run past its timeout, exit 1 (bad input must exit 2), an allocation
// beyond the bound (RLIMIT_AS: the test process's own size plus 1 GiB; a refused allocation
// ends in exit 1 or a signal), or library text or SQL in the output. The findings of issue #34
// are replayed from corpus/regression/ and from generated inputs too large to keep as files.
//
// Release build: about 3300 inputs. Under the sanitizers (HL_FUZZ_SANITIZED) a tenth, without
// RLIMIT_AS (AddressSanitizer reserves terabytes of address space) and with 5x the timeout.
// HL_FUZZ_SCALE multiplies the mutants (e.g. 10 for a long local run), HL_FUZZ_JOBS sets the
// children run at once (default 2), HL_FUZZ_FINDINGS a folder to save failing inputs in.

#include <gtest/gtest.h>

#include <cstdlib>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "cli_child.hpp"
#include "cli_pool.hpp"
#include "hapticlab/test/test_util.hpp"
#include "mutate.hpp"
#include "seeds.hpp"

namespace hapticlab::fuzz::cli_fuzz_test {
namespace {

double EnvNumber(const char* name, double fallback) {
  const char* v = std::getenv(name);
  return v ? std::atof(v) : fallback;
}

std::string Findings() {
  const char* v = std::getenv("HL_FUZZ_FINDINGS");
  return v ? v : "";
}

// A reader of untrusted input as the command line runs it.
struct Reader {
  std::string name;  ///< corpus folder and label
  std::string file;  ///< the input's name in the slot folder
  int mutants = 0;   ///< in a release run
  std::function<std::vector<std::string>(const std::string& slot, const std::string& input, int i)>
      args;
  std::function<void(const std::string& slot)> fixtures = [](const std::string&) {};
};

// Every corpus input as is, then the mutants; returns the findings.
void FuzzReader(const Reader& r, const std::vector<std::string>& seeds, std::uint64_t seed) {
  ASSERT_FALSE(seeds.empty()) << r.name;
  test::TempDir dir;
  Pool pool(static_cast<int>(EnvNumber("HL_FUZZ_JOBS", 2)), CliLimits(10), dir.path());
  int mutants = static_cast<int>(r.mutants * EnvNumber("HL_FUZZ_SCALE", 1));
  if (kSanitized) mutants = std::max(10, mutants / 10);
  const int total = static_cast<int>(seeds.size()) + mutants;
  std::mt19937_64 rng(seed);
  const auto findings = pool.Run(
      total,
      [&](int i, const std::string& slot) {
        std::string input;
        if (i < static_cast<int>(seeds.size())) {
          input = seeds[static_cast<std::size_t>(i)];
        } else {
          input = Mutate(seeds[static_cast<std::size_t>(rng() % seeds.size())], rng);
          if (rng() % 4 == 0) input = Mutate(input, rng);  // stack mutations now and then
        }
        r.fixtures(slot);
        const std::string path = slot + "/" + r.file;
        test::WriteFile(path, input);
        return Job{.args = r.args(slot, path, i), .input = input};
      },
      r.name, Findings());
  std::printf("%s: %d inputs through the CLI, slowest %.2f s\n", r.name.c_str(), total,
              pool.slowest_s());
  ::testing::Test::RecordProperty("inputs", total);
  EXPECT_TRUE(findings.empty()) << findings.size() << " findings, the first:\n" << findings.front();
}

std::vector<std::string> Photometric(const std::string& slot, const std::string& lights) {
  return {"model", "photometric", "--images", slot, "--lights",
          lights,  "--pitch-m",   "1e-4",     "-o", slot + "/h.f32"};
}

TEST(CliFuzz, Protocol) {
  FuzzReader(
      {.name = "protocol",
       .file = "p.toml",
       .mutants = 500,
       .args = [](const std::string&, const std::string& in, int) -> std::vector<std::string> {
         return {"study", "validate", in};
       },
       .fixtures = WriteStudyFiles},
      CorpusFiles("protocol"), 11);
}

TEST(CliFuzz, Rig) {
  FuzzReader(
      {.name = "rig",
       .file = "rig.toml",
       .mutants = 300,
       .args = [](const std::string&, const std::string& in, int) -> std::vector<std::string> {
         return {"rig", "show", in, "--json"};
       }},
      CorpusFiles("rig"), 12);
}

TEST(CliFuzz, Material) {
  FuzzReader(
      {.name = "material",
       .file = "m.toml",
       .mutants = 400,
       .args = [](const std::string&, const std::string& in, int) -> std::vector<std::string> {
         return {"model", "check", in};
       }},
      CorpusFiles("material"), 13);
}

TEST(CliFuzz, LightsFile) {
  FuzzReader({.name = "lights",
              .file = "lights.txt",
              .mutants = 300,
              .args = [](const std::string& slot, const std::string& in,
                         int) { return Photometric(slot, in); },
              .fixtures = WriteImages},
             CorpusFiles("lights"), 14);
}

TEST(CliFuzz, Image) {
  // The mutated image is i0.tga; i1 and i2 and the lights file stay valid.
  FuzzReader({.name = "image",
              .file = "i0.tga",
              .mutants = 300,
              .args = [](const std::string& slot, const std::string&,
                         int) { return Photometric(slot, slot + "/lights.txt"); },
              .fixtures =
                  [](const std::string& slot) {
                    WriteImages(slot);
                    WriteLights(slot);
                  }},
             CorpusFiles("image"), 15);
}

TEST(CliFuzz, MeasurementCsv) {
  FuzzReader(
      {.name = "measurement",
       .file = "d.csv",
       .mutants = 400,
       .args = [](const std::string&, const std::string& in, int) -> std::vector<std::string> {
         return {"measurement", "check", in, "--json"};
       }},
      CorpusFiles("measurement"), 16);
}

TEST(CliFuzz, LongFormatCsv) {
  FuzzReader(
      {.name = "csv",
       .file = "r.csv",
       .mutants = 300,
       .args = [](const std::string&, const std::string& in, int i) -> std::vector<std::string> {
         if (i % 2) return {"stats", "shapiro", "--csv", in, "--dv", "score", "--by", "method"};
         return {"stats", "kruskal", "--csv", in, "--dv", "score", "--group", "method"};
       }},
      CorpusFiles("csv"), 17);
}

TEST(CliFuzz, PennXml) {
  FuzzReader(
      {.name = "penn",
       .file = "Models_F.xml",
       .mutants = 300,
       .args = [](const std::string& slot, const std::string& in, int) -> std::vector<std::string> {
         return {"model", "import-penn", "--xml", in, "-o", slot + "/m.toml"};
       }},
      CorpusFiles("penn"), 18);
}

TEST(CliFuzz, VibrationRecording) {
  FuzzReader(
      {.name = "recording",
       .file = "r.csv",
       .mutants = 150,
       .args = [](const std::string&, const std::string& in, int) -> std::vector<std::string> {
         return {"model", "cutoff", "--recording", in, "--json"};
       }},
      CorpusFiles("recording"), 19);
}

TEST(CliFuzz, StudyDatabase) {
  test::TempDir scratch;
  FuzzReader({.name = "database",
              .file = "s.db",
              .mutants = 300,
              .args = [](const std::string& slot, const std::string& in,
                         int i) -> std::vector<std::string> {
                if (i % 2) return {"study", "status", "--db", in, "--json"};
                return {"export", "--db", in, "--format", "csv", "--out", slot + "/export"};
              }},
             {StudyDatabaseSeed(scratch.path())}, 20);
}

}  // namespace
}  // namespace hapticlab::fuzz::cli_fuzz_test
