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
#include <random>
#include <string>
#include <vector>

#include "hapticlab/test/test_util.hpp"
#include "mutate.hpp"
#include "seeds.hpp"
#include "targets.hpp"

namespace hapticlab::fuzz::fuzz_test {
namespace {

using Target = int (*)(std::string_view, const std::string&);

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
TEST(Fuzz, Protocol) { Fuzz(&Protocol, CorpusFiles("protocol"), Runs(1500), 1); }
TEST(Fuzz, Material) { Fuzz(&Material, CorpusFiles("material"), Runs(1500), 2); }
TEST(Fuzz, Csv) { Fuzz(&Csv, CorpusFiles("csv"), Runs(3000), 3); }
TEST(Fuzz, MeasurementCsv) { Fuzz(&MeasurementCsv, CorpusFiles("measurement"), Runs(3000), 4); }
TEST(Fuzz, PennXml) { Fuzz(&PennXml, CorpusFiles("penn"), Runs(1500), 5); }

TEST(Fuzz, StudyDatabase) {
  // The seed is a small study record built here (a binary file is not kept in the corpus).
  test::TempDir dir;
  Fuzz(&StudyDatabase, {StudyDatabaseSeed(dir.path())}, Runs(300), 6);
}

}  // namespace
}  // namespace hapticlab::fuzz::fuzz_test
