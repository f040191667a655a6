// Deterministic mutation fuzzing of every reader of untrusted input, inside the normal test
// run (so CI runs it under AddressSanitizer + UBSan too). Each reader gets its corpus
// (tests/fuzz/corpus/<reader>/) and a fixed number of mutants from a fixed seed: the same
// inputs on every run, so a failure reproduces. A crash, sanitizer report or std::bad_alloc
// fails the test; the reader's own errors are expected. HL_FUZZ_RUNS overrides the number
// of mutants per reader (e.g. HL_FUZZ_RUNS=100000 for a long local run).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"
#include "targets.hpp"

namespace hapticlab::fuzz {
namespace {

namespace fs = std::filesystem;

using Target = int (*)(std::string_view, const std::string&);

// Tokens the mutator splices in: syntax of the formats and numbers at the edges of ranges.
const std::vector<std::string> kDictionary = {
    "[",
    "]",
    "[[",
    "]]",
    "{",
    "}",
    "=",
    ",",
    ".",
    "\"",
    "'",
    "\"\"\"",
    "'''",
    "#",
    "\n",
    "\r\n",
    "\\",
    "\xEF\xBB\xBF",
    "<",
    ">",
    "</",
    "/>",
    "<value>",
    "</value>",
    "<tri>",
    "<model>",
    "&amp;",
    "<![CDATA[",
    "0",
    "-1",
    "1e10",
    "1e308",
    "-1e308",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "nan",
    "inf",
    "-inf",
    "0x7fffffff",
    "1e-320",
    "true",
    "false",
    "\"\"",
};

std::string Mutate(const std::string& in, std::mt19937_64& rng) {
  std::string s = in;
  auto pick = [&](std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(rng() % n); };
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits; ++e) {
    switch (rng() % 8) {
      case 0:  // flip a bit
        if (!s.empty()) s[pick(s.size())] ^= static_cast<char>(1 << (rng() % 8));
        break;
      case 1:  // a random byte
        if (!s.empty()) s[pick(s.size())] = static_cast<char>(rng() % 256);
        break;
      case 2:
      case 3:  // splice a dictionary token
        s.insert(pick(s.size() + 1), kDictionary[pick(kDictionary.size())]);
        break;
      case 4: {  // erase a range
        const auto at = pick(s.size() + 1);
        s.erase(at, std::min<std::size_t>(1 + pick(32), s.size() - at));
        break;
      }
      case 5: {  // duplicate a range
        const auto at = pick(s.size() + 1);
        const auto piece = s.substr(at, 1 + pick(64));
        s.insert(pick(s.size() + 1), piece);
        break;
      }
      case 6: {  // replace a token with an edge-of-range number
        const auto at = pick(s.size() + 1);
        const auto end = s.find_first_of(" \n,<]", at);
        s.replace(at, (end == std::string::npos ? s.size() : end) - at,
                  kDictionary[28 + pick(kDictionary.size() - 28)]);
        break;
      }
      default: {  // a long run of one token (limits: dotted keys, nesting, long lines)
        const auto& tok = kDictionary[pick(12)];
        std::string run;
        for (std::size_t i = 0, n = 10 + pick(3000); i < n; ++i) run += tok;
        s.insert(pick(s.size() + 1), run);
      }
    }
  }
  return s;
}

std::vector<std::string> Corpus(const std::string& reader) {
  std::vector<std::string> out;
  const fs::path dir = fs::path(HL_SOURCE_DIR) / "tests/fuzz/corpus" / reader;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path());
  std::sort(files.begin(), files.end());  // a fixed order: the same mutants every run
  for (const auto& f : files) out.push_back(test::ReadFile(f.string()));
  return out;
}

int Runs(int fallback) {
  const char* env = std::getenv("HL_FUZZ_RUNS");
  return env ? std::max(1, std::atoi(env)) : fallback;
}

// Every corpus input as is, then `runs` mutants.
void Fuzz(Target target, const std::vector<std::string>& corpus, int runs, std::uint64_t seed) {
  ASSERT_FALSE(corpus.empty());
  test::TempDir dir;
  for (const auto& c : corpus) target(c, dir.path());
  std::mt19937_64 rng(seed);
  for (int i = 0; i < runs; ++i) {
    std::string input = corpus[static_cast<std::size_t>(rng() % corpus.size())];
    input = Mutate(input, rng);
    if (rng() % 4 == 0) input = Mutate(input, rng);  // stack mutations now and then
    target(input, dir.path());
  }
  ::testing::Test::RecordProperty("inputs", static_cast<int>(corpus.size()) + runs);
  std::printf("%s: %d inputs\n", ::testing::UnitTest::GetInstance()->current_test_info()->name(),
              static_cast<int>(corpus.size()) + runs);
}

// Budgets (mutants per reader) keep the whole suite to about 20-40 s under ASan at -O0.
TEST(Fuzz, Protocol) { Fuzz(&Protocol, Corpus("protocol"), Runs(1500), 1); }
TEST(Fuzz, Material) { Fuzz(&Material, Corpus("material"), Runs(1500), 2); }
TEST(Fuzz, Csv) { Fuzz(&Csv, Corpus("csv"), Runs(3000), 3); }
TEST(Fuzz, MeasurementCsv) { Fuzz(&MeasurementCsv, Corpus("measurement"), Runs(3000), 4); }
TEST(Fuzz, PennXml) { Fuzz(&PennXml, Corpus("penn"), Runs(1500), 5); }

TEST(Fuzz, StudyDatabase) {
  // The seed is a small study record built here (a binary file is not kept in the corpus).
  test::TempDir dir;
  const std::string path = dir.File("seed.db");
  {
    db::Database d(path);
    const auto st =
        d.CreateStudy({.name = "f", .protocol_toml = "[study]\nname = \"f\"\n", .seed = 1});
    const auto p = d.AddParticipant({.study_id = st, .code = "P01"});
    const auto se = d.StartSession({.participant_id = p});
    const auto t = d.AddTrial({.session_id = se, .phase = "main", .material = "m"});
    d.StartTrial(t);
    d.InsertTrajectoryChunk({.trial_id = t,
                             .stream = "force",
                             .rate_hz = 1000,
                             .channels = {"a", "b"},
                             .samples = {1, 2, 3, 4},
                             .attempt = 1});
    d.CompleteTrial(t, {{"overall", 50, 1}},
                    {{.trial_id = t,
                      .attempt = 1,
                      .stream = "force",
                      .rate_hz = 1000,
                      .samples_offered = 2,
                      .samples_written = 2}});
    d.Exec("PRAGMA journal_mode = DELETE");  // one self-contained file
  }
  Fuzz(&StudyDatabase, {test::ReadFile(path)}, Runs(300), 6);
}

}  // namespace
}  // namespace hapticlab::fuzz
