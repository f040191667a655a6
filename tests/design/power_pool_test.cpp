// Simulated studies for `study power` (design/src/power_pool.cpp): the felt pool recorded
// through the runner (one temporary database per participant, removed afterwards), the
// protocol's observer, and re-rating the pool into studies of any size: one row per
// participant, main trial and criterion, ratings on the scale that follow the recorded
// feature distances, reproducible from the seed.

#include "hapticlab/design/power_pool.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <numeric>
#include <string>
#include <vector>

#include "hapticlab/core/status.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::design::power_pool_test {
namespace {

namespace fs = std::filesystem;

FeltPool Pool(double distance) {
  FeltPool pool;
  pool.protocol = "p";
  pool.criteria = {"roughness", "overall"};
  pool.observer = sim::LoadProfiles(test::DataPath("protocols/profiles.toml")).observer;
  for (int i = 0; i < 2; ++i)
    pool.participants.push_back({{.plan_index = 0,
                                  .phase = PhaseKind::kReference,
                                  .material = "Cork",
                                  .comparison = "Towel",
                                  .distances = {distance, distance}},
                                 {.plan_index = 1,
                                  .phase = PhaseKind::kMain,
                                  .material = "Cork",
                                  .comparison = "virtual",
                                  .method = "FF",
                                  .distances = {distance, distance}},
                                 {.plan_index = 2,
                                  .phase = PhaseKind::kMain,
                                  .material = "Denim",
                                  .comparison = "virtual",
                                  .method = "Hybrid",
                                  .distances = {distance, distance}}});
  return pool;
}

double Mean(const std::vector<double>& v) {
  return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

TEST(PowerPool, SimulatedStudiesHaveOneRowPerParticipantTrialAndCriterion) {
  const auto pool = Pool(0.5);
  Rng rng(3);
  const auto main = SimulateRatings(pool, pool.observer, 5, rng, true);
  EXPECT_EQ(main.key_names,
            (std::vector<std::string>{"participant", "criterion", "method", "material"}));
  ASSERT_EQ(main.rows(), 5u * 2 * 2);  // 5 participants x 2 main trials x 2 criteria
  EXPECT_EQ(main.Levels("participant"),
            (std::vector<std::string>{"S001", "S002", "S003", "S004", "S005"}));
  EXPECT_EQ(main.Levels("method"), (std::vector<std::string>{"FF", "Hybrid"}));
  for (const double y : main.y) {
    EXPECT_GE(y, pool.scale_min);
    EXPECT_LE(y, pool.scale_max);
  }
  Rng all_rng(3);
  const auto all = SimulateRatings(pool, pool.observer, 5, all_rng, false);
  EXPECT_EQ(all.key_names.size(), 6u);
  EXPECT_EQ(all.rows(), 5u * 3 * 2);  // the reference trial too
  EXPECT_EQ(all.Where({{"phase", "reference"}}).rows(), 5u * 2);
  // The same seed: the same study.
  Rng again(3);
  EXPECT_EQ(SimulateRatings(pool, pool.observer, 5, again, true).y, main.y);
}

TEST(PowerPool, RatingsFollowTheRecordedDistances) {
  // Identical interactions are rated near the observer's upper limit (78 in the test
  // profiles), very different ones near its lower limit (35).
  Rng a(9), b(9);
  const auto same = SimulateRatings(Pool(0), Pool(0).observer, 40, a, true);
  const auto far = SimulateRatings(Pool(50), Pool(50).observer, 40, b, true);
  EXPECT_GT(Mean(same.y), Mean(far.y) + 20) << Mean(same.y) << " vs " << Mean(far.y);
  EXPECT_NEAR(Mean(same.y), 78, 8);
  EXPECT_NEAR(Mean(far.y), 35, 8);
  FeltPool empty;
  Rng c(1);
  EXPECT_THROW(SimulateRatings(empty, {}, 3, c, true), PreconditionError);
}

TEST(PowerPool, RecordsThePoolThroughTheRunnerAndCleansUp) {
  test::TempDir dir;
  // One material, one method, one main trial of 0.1 s per participant.
  // The test profiles with another upper limit: the observer must come from this file.
  std::string profiles = test::ReadFile(test::DataPath("protocols/profiles.toml"));
  const auto at = profiles.find("upper = 78.0");
  ASSERT_NE(at, std::string::npos);
  profiles.replace(at, 12, "upper = 81.5");
  test::WriteFile(dir.File("profiles.toml"), profiles);
  std::ofstream(dir.File("p.toml")) << R"([study]
name = "pool-test"
seed = 5
criteria = ["roughness", "overall"]
stimulus_duration_s = 0.1
profiles = "profiles.toml"

[[material]]
id = "Cork"

[[method]]
name = "FF"
algorithm = "fric2"
vibration = false

[[phase]]
kind = "main"
repetitions = 1
)";
  const auto p = protocols::LoadProtocol(dir.File("p.toml"));
  EXPECT_EQ(ProtocolObserver(p).upper, 81.5);  // the profiles file's [observer], beside p.toml
  std::vector<std::string> log;
  const auto pool = RecordFeltPool(
      p, 2, 2, [&](const std::string& line) { log.push_back(line); }, 3);
  EXPECT_EQ(pool.protocol, "pool-test");
  EXPECT_EQ(pool.criteria, p.criteria);
  EXPECT_EQ(pool.observer.upper, 81.5);
  ASSERT_EQ(pool.participants.size(), 2u);
  for (const auto& trials : pool.participants) {
    ASSERT_EQ(trials.size(), 1u);
    EXPECT_EQ(trials[0].phase, PhaseKind::kMain);
    EXPECT_EQ(trials[0].material, "Cork");
    EXPECT_EQ(trials[0].distances.size(), 2u);
  }
  EXPECT_EQ(log.size(), 2u);
  // The temporary databases are gone.
  const std::string mine = "hapticlab-power-" + std::to_string(::getpid()) + "-";
  for (const auto& e : fs::directory_iterator(fs::temp_directory_path()))
    EXPECT_NE(e.path().filename().string().rfind(mine, 0), 0u) << e.path();
  EXPECT_THROW(RecordFeltPool(p, 0), PreconditionError);
}

}  // namespace
}  // namespace hapticlab::design::power_pool_test
