// hapticlab model score / identify through the command line (apps/hapticlab/cmd_model_score.cpp)
// on WAV recordings of two textures written here with libsndfile.

#include <gtest/gtest.h>
#include <sndfile.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "hapticlab/test/sound_file.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_model_score_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

// A mono 16-bit 10 kHz WAV of a resonance at `peak_hz`, from a seeded LCG.
void WriteTexture(const std::string& path, double peak_hz, std::uint64_t seed, double gain) {
  const double c1 = 2 * 0.97 * std::cos(2 * std::numbers::pi * peak_hz / 10000), c2 = -0.97 * 0.97;
  test::WriteSound(path, SF_FORMAT_WAV | SF_FORMAT_PCM_16, 10000, 1,
                   test::Ar2LcgNoise(30000, seed, c1, c2, gain));
}

int RunCli(const std::string& args, std::string* out) {
  return test::RunCommand(Cli() + " " + args + " 2>&1", out);
}

TEST(ModelScoreCli, ScoresAndIdentifiesTexturesFromWavFiles) {
  test::TempDir dir;
  std::filesystem::create_directories(dir.File("models"));
  for (const auto& [name, peak] : {std::pair{"low", 150.0}, std::pair{"high", 600.0}}) {
    std::filesystem::create_directories(dir.File(std::string("rec_") + name));
    WriteTexture(dir.File(std::string("rec_") + name + "/a.wav"), peak, 10, 0.01);
    std::string out;
    ASSERT_EQ(RunCli("model fit-vibration --recordings " + dir.File(std::string("rec_") + name) +
                         " --speed 0.1 --force 1 --uncalibrated -o " +
                         dir.File(std::string("models/") + name + ".toml"),
                     &out),
              0)
        << out;
  }
  // A fresh recording of the low texture, three times louder (another session's level).
  WriteTexture(dir.File("probe.wav"), 150.0, 99, 0.03);
  std::string out;
  ASSERT_EQ(RunCli("model score --model " + dir.File("models/low.toml") + " --recording " +
                       dir.File("probe.wav") + " --json",
                   &out),
            0)
      << out;
  const auto s = nlohmann::json::parse(out);
  EXPECT_EQ(s["kind"], "ar bank");
  EXPECT_EQ(s["condition_from_model"], true);  // an unlabelled WAV, a one-cell bank
  EXPECT_NEAR(s["level_ratio"].get<double>(), 1.0 / 3, 0.08);
  ASSERT_EQ(RunCli("model score --level-normalised --model " + dir.File("models/low.toml") +
                       " --recording " + dir.File("probe.wav") + " --json",
                   &out),
            0)
      << out;
  EXPECT_LT(nlohmann::json::parse(out)["es"].get<double>(), s["es"].get<double>());
  ASSERT_EQ(RunCli("model identify --level-normalised --models " + dir.File("models") +
                       " --recording " + dir.File("probe.wav") + " --json",
                   &out),
            0)
      << out;
  const auto id = nlohmann::json::parse(out);
  ASSERT_EQ(id["ranking"].size(), 2u);
  EXPECT_EQ(id["ranking"][0]["model"], dir.File("models/low.toml"));
  EXPECT_LT(2 * id["ranking"][0]["es"].get<double>(), id["ranking"][1]["es"].get<double>());
  // Text output names the winner; a folder without models is bad input.
  ASSERT_EQ(RunCli("model identify --models " + dir.File("models") + " --recording " +
                       dir.File("probe.wav"),
                   &out),
            0);
  EXPECT_NE(out.find("uncalibrated"), std::string::npos) << out;
  std::filesystem::create_directories(dir.File("none"));
  EXPECT_EQ(RunCli("model identify --models " + dir.File("none") + " --recording " +
                       dir.File("probe.wav"),
                   &out),
            2);
  EXPECT_NE(out.find("no .toml models"), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab::cmd_model_score_test
