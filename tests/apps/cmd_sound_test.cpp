// WAV/FLAC and vibration-only recordings through every command that reads recordings:
// model fit-vibration, cv-vibration, fit-neural, cutoff, measurement check (accepted), and
// fit, compare, diagnose (refused with the file and what is missing). Files are written here
// with libsndfile.

#include <gtest/gtest.h>
#include <sndfile.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hapticlab/test/sound_file.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_sound_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

// An AR(2) resonance whose level grows with speed, from a seeded LCG (no library RNG).
std::vector<double> Resonance(std::size_t n, std::uint64_t seed, double gain) {
  return test::Ar2LcgNoise(n, seed, 1.6, -0.9, gain);
}

void WriteWav3(const std::string& path, std::uint64_t seed, double gain) {
  // Three axes: x and z share a resonance, y has its own.
  const auto a = Resonance(20000, seed, gain), b = Resonance(20000, seed + 100, gain);
  std::vector<double> inter;
  for (std::size_t i = 0; i < a.size(); ++i) inter.insert(inter.end(), {a[i], b[i], 0.5 * a[i]});
  test::WriteSound(path, SF_FORMAT_WAV | SF_FORMAT_PCM_16, 10000, 3, inter);
}

// A 2 x 2 grid of 3-axis WAVs with sidecars, and a second recording at (0.10 m/s, 1.0 N).
void WriteWavGrid(const std::string& dir) {
  std::filesystem::create_directories(dir);
  int k = 0;
  for (double v : {0.05, 0.10})
    for (double f : {0.5, 1.0}) {
      const std::string name = dir + "/c" + std::to_string(k);
      WriteWav3(name + ".wav", 1000 + static_cast<std::uint64_t>(k), 0.01 + 0.05 * v);
      test::WriteFile(name + ".toml", "[recording]\nspeed_mps = " + std::to_string(v) +
                                          "\nforce_N = " + std::to_string(f) +
                                          "\nscale_mps2 = 20.0\naxes = [1, 2, 3]\n");
      ++k;
    }
  WriteWav3(dir + "/c3b.wav", 77, 0.015);
  test::WriteFile(dir + "/c3b.toml",
                  "[recording]\nspeed_mps = 0.1\nforce_N = 1.0\nscale_mps2 = 20.0\n");
}

// The same grid as vibration-only CSV (t_s, acc_mps2 with condition metadata).
void WriteCsvGrid(const std::string& dir) {
  std::filesystem::create_directories(dir);
  int k = 0;
  for (double v : {0.05, 0.10})
    for (double f : {0.5, 1.0}) {
      std::string s = "# hapticlab-measurement v1\n# speed_mps: " + std::to_string(v) +
                      "\n# force_N: " + std::to_string(f) + "\nt_s,acc_mps2\n";
      const auto x = Resonance(8000, 500 + static_cast<std::uint64_t>(k), 1.0 + v);
      for (std::size_t i = 0; i < x.size(); ++i)
        s += std::to_string(static_cast<double>(i) / 4000.0) + "," + std::to_string(x[i]) + "\n";
      test::WriteFile(dir + "/v" + std::to_string(k++) + ".csv", s);
    }
}

int RunCli(const std::string& args, std::string* out) {
  return test::RunCommand(Cli() + " " + args + " 2>&1", out);
}

TEST(SoundCli, WavRecordingsThroughTheVibrationCommands) {
  test::TempDir dir;
  WriteWavGrid(dir.File("wav"));
  std::string out;
  ASSERT_EQ(RunCli("model fit-vibration --recordings " + dir.File("wav") + " --order 4 -o " +
                       dir.File("bank.toml"),
                   &out),
            0)
      << out;
  EXPECT_NE(out.find("5 recordings -> 4 cells (grid)"), std::string::npos) << out;  // pooled
  EXPECT_EQ(out.find("uncalibrated"), std::string::npos) << out;
  ASSERT_EQ(RunCli("model cv-vibration --recordings " + dir.File("wav") +
                       " --order 4 --train-speeds 0.05,0.1 --train-forces 0.5,1 --json",
                   &out),
            0)
      << out;
  const auto cv = nlohmann::json::parse(out);
  ASSERT_EQ(cv["conditions"].size(), 5u);
  EXPECT_EQ(cv["conditions"][3]["file"], dir.File("wav/c3.wav"));
  EXPECT_EQ(cv["conditions"][4]["file"], dir.File("wav/c3b.wav"));
  EXPECT_EQ(cv["calibrated"], true);
  ASSERT_EQ(RunCli("model fit-neural --recordings " + dir.File("wav") +
                       " --topology decomposed --epochs 1 --threads 1 -o " + dir.File("n.toml"),
                   &out),
            0)
      << out;
  EXPECT_NE(out.find("5 recordings (2 speeds x 2 forces)"), std::string::npos) << out;
  ASSERT_EQ(RunCli("model cutoff --recording " + dir.File("wav/c0.wav") + " --json", &out), 0)
      << out;
  EXPECT_FALSE(nlohmann::json::parse(out)["tried"].empty());
  ASSERT_EQ(RunCli("measurement check --json " + dir.File("wav/c0.wav"), &out), 0) << out;
  const auto check = nlohmann::json::parse(out);
  EXPECT_EQ(check["kind"], "vibration");
  EXPECT_EQ(check["axes"], 3);
  EXPECT_EQ(check["reduction"], "dft321");
  EXPECT_EQ(check["rate_hz"], 10000.0);
  EXPECT_EQ(check["condition"]["speed_mps"], 0.05);
  EXPECT_EQ(check["format"], "WAV, 16-bit PCM, 3 channels");
}

TEST(SoundCli, UncalibratedAndUnlabelledSayItOrAreRefused) {
  test::TempDir dir;
  std::filesystem::create_directories(dir.File("u"));
  WriteWav3(dir.File("u/a.wav"), 5, 0.02);
  std::string out;
  ASSERT_EQ(RunCli("measurement check " + dir.File("u/a.wav"), &out), 0) << out;
  EXPECT_NE(out.find("unlabelled"), std::string::npos) << out;
  EXPECT_NE(out.find("uncalibrated"), std::string::npos) << out;
  // No condition: the fit says which file and what to give.
  EXPECT_EQ(
      RunCli("model fit-vibration --recordings " + dir.File("u") + " -o " + dir.File("b.toml"),
             &out),
      2);
  EXPECT_NE(out.find(dir.File("u/a.wav")), std::string::npos) << out;
  EXPECT_NE(out.find("--speed"), std::string::npos) << out;
  // With the condition on the command line it fits, and the bank says it is uncalibrated.
  ASSERT_EQ(RunCli("model fit-vibration --recordings " + dir.File("u") +
                       " --speed 0.1 --force 1 --uncalibrated --order 3 -o " + dir.File("b.toml"),
                   &out),
            0)
      << out;
  EXPECT_NE(out.find("uncalibrated"), std::string::npos) << out;
  EXPECT_NE(test::ReadFile(dir.File("b.toml")).find("# uncalibrated"), std::string::npos);
  // Contradicting flags.
  EXPECT_EQ(
      RunCli("model cutoff --recording " + dir.File("u/a.wav") + " --scale 2 --uncalibrated", &out),
      2);
  EXPECT_NE(out.find("--uncalibrated"), std::string::npos) << out;
}

TEST(SoundCli, VibrationOnlyCsvThroughEveryCommand) {
  test::TempDir dir;
  WriteCsvGrid(dir.File("csv"));
  std::string out;
  ASSERT_EQ(RunCli("model fit-vibration --recordings " + dir.File("csv") + " --order 4 -o " +
                       dir.File("bank.toml"),
                   &out),
            0)
      << out;
  ASSERT_EQ(RunCli("model cv-vibration --recordings " + dir.File("csv") +
                       " --order 4 --train-speeds 0.05,0.1 --train-forces 0.5,1",
                   &out),
            0)
      << out;
  EXPECT_NE(out.find(dir.File("csv/v2.csv")), std::string::npos) << out;
  ASSERT_EQ(RunCli("model fit-neural --recordings " + dir.File("csv") +
                       " --topology decomposed --epochs 1 --threads 1 -o " + dir.File("n.toml"),
                   &out),
            0)
      << out;
  ASSERT_EQ(RunCli("model cutoff --recording " + dir.File("csv/v0.csv"), &out), 0) << out;
  ASSERT_EQ(RunCli("measurement check " + dir.File("csv/v0.csv"), &out), 0) << out;
  EXPECT_NE(out.find("vibration only"), std::string::npos) << out;
  EXPECT_NE(out.find("0.05 m/s, 0.5 N"), std::string::npos) << out;
}

TEST(SoundCli, WorkbenchRefusesVibrationOnlyFilesNamingThem) {
  test::TempDir dir;
  WriteCsvGrid(dir.File("csv"));
  std::filesystem::create_directories(dir.File("wav"));
  WriteWav3(dir.File("wav/a.wav"), 9, 0.02);
  test::WriteFile(dir.File("m.toml"),
                  "name = \"x\"\n[contact]\ntexture_K = 100.0\n[friction]\nkappa_N_per_m = 100.0\n"
                  "mu_k = 0.2\n");
  for (const std::string& file : {dir.File("csv/v0.csv"), dir.File("wav/a.wav")}) {
    for (const char* cmd : {"compare", "diagnose --quiet"}) {
      std::string out;
      EXPECT_EQ(
          RunCli(std::string(cmd) + " --model " + dir.File("m.toml") + " --measurement " + file,
                 &out),
          2)
          << cmd << " " << file << ": " << out;
      EXPECT_NE(out.find(file), std::string::npos) << out;
      EXPECT_NE(out.find("vibration only"), std::string::npos) << out;
      EXPECT_NE(out.find("x_m"), std::string::npos) << out;
    }
  }
}

TEST(SoundCli, BadSoundInputExitsTwoNamingFileAndField) {
  test::TempDir dir;
  WriteWavGrid(dir.File("wav"));
  std::string out;
  test::WriteFile(dir.File("wav/c1.toml"), "[recording]\nspeed_mps = 0.05\nforse_N = 1.0\n");
  EXPECT_EQ(
      RunCli("model fit-vibration --recordings " + dir.File("wav") + " -o " + dir.File("b.toml"),
             &out),
      2);
  EXPECT_NE(out.find(dir.File("wav/c1.toml") + ":3: recording.forse_N"), std::string::npos) << out;
  const auto wav = dir.File("wav/c0.wav");
  std::filesystem::resize_file(wav, std::filesystem::file_size(wav) / 3);
  EXPECT_EQ(RunCli("model cutoff --recording " + wav, &out), 2);
  EXPECT_NE(out.find(wav + ": frames: truncated"), std::string::npos) << out;
  EXPECT_EQ(RunCli("measurement check " + wav, &out), 2);
  EXPECT_NE(out.find(wav), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab::cmd_sound_test
