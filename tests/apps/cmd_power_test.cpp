// `hapticlab study power`: the JSON's keys, the same result whatever the thread count, and
// two shards merged (`--merge`) equal to the unsharded run.

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_power_test {
namespace {

using nlohmann::json;

std::string Power() {
  return std::string(HL_CLI_PATH) + " study power " + test::DataPath("protocols/small.toml") +
         " --participants 3,5 --simulations 24 --pool 2 --seed 9 --quiet --observer builtin";
}

// A protocol with its own participant code pattern and an observer file of its own.
struct CustomStudy {
  test::TempDir dir;
  std::string protocol = dir.File("nu.toml"), observer = dir.File("obs.toml");
  explicit CustomStudy(bool with_observer) {
    std::filesystem::copy_file(test::DataPath("protocols/profiles.toml"),
                               dir.File("profiles.toml"));
    test::WriteFile(observer, "# a test observer\n[observer]\nupper = 80.0\nlower = 30.0\n");
    std::string text = test::ReadFile(test::DataPath("protocols/small.toml"));
    text.replace(text.find("seed = 42"), 9,
                 std::string("seed = 42\nparticipant_code = \"^NU[0-9]{3}$\"") +
                     (with_observer ? "\nobserver = \"obs.toml\"" : ""));
    test::WriteFile(protocol, text);
  }
  std::string Power(const std::string& extra) const {
    return std::string(HL_CLI_PATH) + " study power " + protocol +
           " --participants 3,4 --simulations 4 --pool 1 --quiet" + extra;
  }
};

// The file's SHA-256 as coreutils computes it (an independent reader).
std::string Sha256sum(const std::string& file) {
  std::string out;
  EXPECT_EQ(test::RunCommand("sha256sum " + file, &out), 0);
  return out.substr(0, 64);
}

TEST(PowerCli, ACustomCodePatternAnswersAndTheObserverIsNamed) {
  CustomStudy s(true);
  std::string out;
  ASSERT_EQ(
      test::RunCommand(s.Power(" --json --plot " + s.dir.File("curves") + " 2>/dev/null"), &out), 0)
      << out;
  const json j = json::parse(out);
  EXPECT_EQ(j["observer"]["file"], s.observer);
  EXPECT_EQ(j["observer"]["sha256"], Sha256sum(s.observer));
  EXPECT_EQ(j["observer"]["model"], s.observer + " (sha256 " + Sha256sum(s.observer) + ")");
  const std::string svg = test::ReadFile(s.dir.File("curves.svg"));
  EXPECT_NE(
      svg.find("<desc>observer: " + s.observer + " (sha256 " + Sha256sum(s.observer) + ")</desc>"),
      std::string::npos);
  ASSERT_EQ(test::RunCommand(s.Power(""), &out), 0) << out;
  EXPECT_NE(out.find("observer: " + s.observer + " (sha256 "), std::string::npos) << out;
}

TEST(PowerCli, WithoutAnObserverItRefusesUnlessTheBuiltinOneIsAskedFor) {
  CustomStudy s(false);
  std::string out;
  EXPECT_EQ(test::RunCommand(s.Power(""), &out), 2) << out;
  EXPECT_NE(out.find(s.protocol + ": --observer: the protocol names no simulated observer"),
            std::string::npos)
      << out;
  ASSERT_EQ(test::RunCommand(s.Power(" --observer builtin --json 2>/dev/null"), &out), 0) << out;
  const json j = json::parse(out);
  EXPECT_EQ(j["observer"]["model"], "built-in uncalibrated");
  EXPECT_TRUE(j["observer"]["file"].is_null());
  // An observer file given on the command line is named as given.
  ASSERT_EQ(test::RunCommand(s.Power(" --observer " + s.observer + " --json 2>/dev/null"), &out), 0)
      << out;
  EXPECT_EQ(json::parse(out)["observer"]["sha256"], Sha256sum(s.observer));
}

TEST(PowerCli, JsonShardsMergeAndThreads) {
  test::TempDir dir;
  std::string a, b, out;
  ASSERT_EQ(test::RunCommand(Power() + " --json --threads 1 2>/dev/null", &a), 0) << a;
  ASSERT_EQ(test::RunCommand(Power() + " --json --threads 2 2>/dev/null", &b), 0) << b;
  EXPECT_EQ(a, b);
  const json j = json::parse(a);
  for (const char* k : {"protocol", "observer", "simulations", "seed", "rows"})
    EXPECT_TRUE(j.contains(k)) << k;
  EXPECT_EQ(j["simulations"], 24);
  EXPECT_EQ(j["seed"], 9);
  ASSERT_EQ(j["rows"].size(), 2u);
  EXPECT_EQ(j["rows"][0]["participants"], 3);
  ASSERT_FALSE(j["rows"][0]["effects"].empty());
  for (const auto& e : j["rows"][1]["effects"]) {
    for (const char* k : {"criterion", "effect", "power", "ci_low", "ci_high", "mean_pes"})
      EXPECT_TRUE(e.contains(k)) << k;
    EXPECT_LE(e["ci_low"].get<double>(), e["power"].get<double>());
    EXPECT_GE(e["ci_high"].get<double>(), e["power"].get<double>());
  }
  for (int s = 0; s < 2; ++s)
    ASSERT_EQ(test::RunCommand(Power() + " --shard " + std::to_string(s) + "/2 --out " +
                                   dir.File("part" + std::to_string(s) + ".json"),
                               &out),
              0)
        << out;
  ASSERT_EQ(
      test::RunCommand(std::string(HL_CLI_PATH) + " study power --merge " + dir.File("part0.json") +
                           " " + dir.File("part1.json") + " --json --plot " + dir.File("curves"),
                       &out),
      0)
      << out;
  const json m = json::parse(out);
  ASSERT_EQ(m["rows"].size(), j["rows"].size());
  for (std::size_t r = 0; r < m["rows"].size(); ++r) {
    ASSERT_EQ(m["rows"][r]["effects"].size(), j["rows"][r]["effects"].size());
    for (std::size_t e = 0; e < j["rows"][r]["effects"].size(); ++e) {
      const auto &x = m["rows"][r]["effects"][e], &y = j["rows"][r]["effects"][e];
      EXPECT_EQ(x["effect"], y["effect"]);
      EXPECT_EQ(x["hits"], y["hits"]);
      EXPECT_EQ(x["runs"], y["runs"]);
      EXPECT_EQ(x["power"], y["power"]);
      EXPECT_EQ(x["ci_low"], y["ci_low"]);
      // Summed in another order: equal to rounding.
      EXPECT_NEAR(x["mean_pes"].get<double>(), y["mean_pes"].get<double>(), 1e-12);
    }
  }
  EXPECT_TRUE(std::filesystem::exists(dir.File("curves.svg")));
  // Only one of the shards: refused.
  EXPECT_EQ(test::RunCommand(
                std::string(HL_CLI_PATH) + " study power --merge " + dir.File("part0.json"), &out),
            2)
      << out;
  EXPECT_EQ(test::RunCommand(Power() + " --shard 2/2", &out), 2) << out;
}

}  // namespace
}  // namespace hapticlab::cmd_power_test
