// WAV and FLAC recordings (sound_recording.hpp) on files libsndfile writes here: 16-bit,
// 24-bit and float, mono and three channels, at 10 kHz and 44.1 kHz; sidecars; bad files;
// several recordings of one condition pooled by the bank fit.

#include "hapticlab/modeling/sound_recording.hpp"

#include <gtest/gtest.h>
#include <sndfile.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/modeling/vibration.hpp"
#include "hapticlab/test/sound_file.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::modeling::sound_recording_test {
namespace {

using test::WriteSound;

// An AR(2) resonance (1.6, -0.9) driven by seeded noise, peak around 0.4.
std::vector<double> Resonance(std::size_t n, std::uint64_t seed, double gain = 0.05) {
  Rng rng(seed);
  std::vector<double> x(n);
  double a1 = 0, a2 = 0;
  for (auto& v : x) {
    v = 1.6 * a1 - 0.9 * a2 + gain * rng.Normal();
    a2 = a1;
    a1 = v;
  }
  return x;
}

Diagnostic FirstDiagnostic(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.diagnostics().front();
  }
  ADD_FAILURE() << "no InputError";
  return {};
}

TEST(SoundRecording, Mono16BitAt10kHzWithSidecar) {
  test::TempDir dir;
  std::vector<double> x(20000);
  for (std::size_t i = 0; i < x.size(); ++i)
    x[i] = 0.5 * std::sin(2 * std::numbers::pi * 180.0 * static_cast<double>(i) / 10000.0);
  WriteSound(dir.File("a.wav"), SF_FORMAT_WAV | SF_FORMAT_PCM_16, 10000, 1, x);
  test::WriteFile(dir.File("a.toml"),
                  "[recording]\nspeed_mps = 0.08\nforce_N = 1.2\nscale_mps2 = 9.81\n");
  const Recording r = LoadRecording(dir.File("a.wav"));
  EXPECT_EQ(r.rate_hz, 10000.0);
  EXPECT_TRUE(r.labelled);
  EXPECT_TRUE(r.calibrated);
  EXPECT_EQ(r.speed_mps, 0.08);
  EXPECT_EQ(r.force_N, 1.2);
  ASSERT_EQ(r.acc.size(), x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    ASSERT_NEAR(r.acc[i], 9.81 * x[i], 9.81 / 32768.0) << i;  // one 16-bit step
}

TEST(SoundRecording, ThreeChannels24BitAt44kHzAreReducedByDft321) {
  test::TempDir dir;
  const auto x = Resonance(44100, 2, 0.01);
  // Signal on channel 2 only: DFT321 gives it back as it is.
  std::vector<double> one, equal;
  for (const double v : x) {
    one.insert(one.end(), {0.0, v, 0.0});
    equal.insert(equal.end(), {v, v, v});
  }
  WriteSound(dir.File("one.wav"), SF_FORMAT_WAV | SF_FORMAT_PCM_24, 44100, 3, one);
  WriteSound(dir.File("eq.wav"), SF_FORMAT_WAV | SF_FORMAT_PCM_24, 44100, 3, equal);
  const double lsb = std::ldexp(1.0, -23);
  const Recording r1 = LoadRecording(dir.File("one.wav"));  // no sidecar: defaults
  EXPECT_FALSE(r1.labelled);
  EXPECT_FALSE(r1.calibrated);
  EXPECT_EQ(r1.channels, 3);
  EXPECT_EQ(r1.rate_hz, 44100.0);
  for (std::size_t i = 0; i < x.size(); ++i) ASSERT_NEAR(r1.acc[i], x[i], 2 * lsb) << i;
  const Recording r3 = LoadRecording(dir.File("eq.wav"));
  for (std::size_t i = 0; i < x.size(); ++i)
    ASSERT_NEAR(r3.acc[i], std::sqrt(3.0) * x[i], 4 * lsb) << i;
}

TEST(SoundRecording, FloatWavPicksTheAxisItIsToldAndFlacReadsBack) {
  test::TempDir dir;
  const auto x = Resonance(5000, 3, 0.02);
  std::vector<double> inter;
  for (const double v : x) inter.insert(inter.end(), {0.25, -v, v});
  WriteSound(dir.File("f.wav"), SF_FORMAT_WAV | SF_FORMAT_FLOAT, 10000, 3, inter);
  SoundLabels flags;  // the command line's: channel 3 alone, 0.05 m/s, 2 N, scale 3
  flags.axes = {3};
  flags.speed_mps = 0.05;
  flags.force_N = 2.0;
  flags.scale_mps2 = 3.0;
  const Recording r = LoadRecording(dir.File("f.wav"), flags);
  EXPECT_EQ(r.channels, 1);
  EXPECT_EQ(r.force_N, 2.0);
  for (std::size_t i = 0; i < x.size(); ++i)
    ASSERT_NEAR(r.acc[i], 3.0 * static_cast<float>(x[i]), 1e-6) << i;
  // A sidecar overrides the command line key by key.
  test::WriteFile(dir.File("f.toml"), "[recording]\naxes = [2]\ncalibration = \"uncalibrated\"\n");
  const Recording s = LoadRecording(dir.File("f.wav"), flags);
  EXPECT_FALSE(s.calibrated);
  EXPECT_EQ(s.force_N, 2.0);
  EXPECT_NEAR(s.acc[10], -static_cast<float>(x[10]), 1e-7);

  WriteSound(dir.File("m.flac"), SF_FORMAT_FLAC | SF_FORMAT_PCM_16, 44100, 1, x);
  EXPECT_EQ(ProbeSound(dir.File("m.flac")).format, "FLAC, 16-bit PCM");
  const Recording m = LoadRecording(dir.File("m.flac"));
  ASSERT_EQ(m.acc.size(), x.size());
  for (std::size_t i = 0; i < x.size(); ++i) ASSERT_NEAR(m.acc[i], x[i], 1.0 / 32768) << i;
}

TEST(SoundRecording, LongThreeAxisFilesStreamThroughDft321) {
  // Above 2^21 frames the reduction runs frame by frame; equal axes still give sqrt(3) x.
  test::TempDir dir;
  const auto x = Resonance((std::size_t{1} << 21) + 12345, 4, 0.005);
  std::vector<double> inter;
  inter.reserve(3 * x.size());
  for (const double v : x) inter.insert(inter.end(), {v, v, v});
  WriteSound(dir.File("long.wav"), SF_FORMAT_WAV | SF_FORMAT_FLOAT, 44100, 3, inter);
  const Recording r = LoadRecording(dir.File("long.wav"));
  ASSERT_EQ(r.acc.size(), x.size());
  double worst = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    worst = std::max(worst, std::abs(r.acc[i] - std::sqrt(3.0) * static_cast<float>(x[i])));
  EXPECT_LT(worst, 1e-5);
}

TEST(SoundRecording, BadFilesNameTheFileAndField) {
  test::TempDir dir;
  const auto x = Resonance(8000, 5, 0.02);
  WriteSound(dir.File("t.wav"), SF_FORMAT_WAV | SF_FORMAT_PCM_16, 10000, 1, x);
  // Truncated in the data: half the bytes.
  const auto size = std::filesystem::file_size(dir.File("t.wav"));
  std::filesystem::resize_file(dir.File("t.wav"), size / 2);
  auto d = FirstDiagnostic([&] { LoadRecording(dir.File("t.wav")); });
  EXPECT_EQ(d.file, dir.File("t.wav"));
  EXPECT_EQ(d.field, "frames");
  EXPECT_NE(d.message.find("truncated"), std::string::npos) << d.message;
  // Truncated inside the header, and not a sound file at all.
  std::filesystem::resize_file(dir.File("t.wav"), 20);
  d = FirstDiagnostic([&] { LoadRecording(dir.File("t.wav")); });
  EXPECT_EQ(d.file, dir.File("t.wav"));
  test::WriteFile(dir.File("text.wav"), "hello, this is no sound file\n");
  d = FirstDiagnostic([&] { LoadRecording(dir.File("text.wav")); });
  EXPECT_EQ(d.file, dir.File("text.wav"));
  // A sidecar with a misspelt key, one with a wrong type, a contradiction.
  WriteSound(dir.File("s.wav"), SF_FORMAT_WAV | SF_FORMAT_PCM_16, 10000, 1, x);
  test::WriteFile(dir.File("s.toml"), "[recording]\nforce_N = 1.0\nsped_mps = 0.1\n");
  d = FirstDiagnostic([&] { LoadRecording(dir.File("s.wav")); });
  EXPECT_EQ(d.file, dir.File("s.toml"));
  EXPECT_EQ(d.line, 3);
  EXPECT_EQ(d.field, "recording.sped_mps");
  test::WriteFile(dir.File("s.toml"), "[recording]\naxes = \"xyz\"\n");
  d = FirstDiagnostic([&] { LoadRecording(dir.File("s.wav")); });
  EXPECT_EQ(d.field, "recording.axes");
  test::WriteFile(dir.File("s.toml"),
                  "[recording]\ncondition = \"unlabelled\"\nspeed_mps = 0.1\nforce_N = 1.0\n");
  d = FirstDiagnostic([&] { LoadRecording(dir.File("s.wav")); });
  EXPECT_EQ(d.file, dir.File("s.toml"));
  EXPECT_EQ(d.field, "condition");
  // An axis the file does not have; two channels without axes.
  test::WriteFile(dir.File("s.toml"), "[recording]\naxes = [2]\n");
  d = FirstDiagnostic([&] { LoadRecording(dir.File("s.wav")); });
  EXPECT_EQ(d.field, "axes");
  std::vector<double> st;
  for (const double v : x) st.insert(st.end(), {v, v});
  WriteSound(dir.File("st.wav"), SF_FORMAT_WAV | SF_FORMAT_PCM_16, 10000, 2, st);
  d = FirstDiagnostic([&] { LoadRecording(dir.File("st.wav")); });
  EXPECT_EQ(d.field, "axes");
  // Clipped: a 16-bit file with a run at full scale.
  std::vector<double> clip(x);
  for (std::size_t i = 100; i < 200; ++i) clip[i] = 1.0;
  WriteSound(dir.File("c.wav"), SF_FORMAT_WAV | SF_FORMAT_PCM_16, 10000, 1, clip);
  d = FirstDiagnostic([&] { LoadRecording(dir.File("c.wav")); });
  EXPECT_EQ(d.field, "channel 1");
  EXPECT_NE(d.message.find("clipped"), std::string::npos);
}

TEST(SoundRecording, FoldersMixSoundAndCsvAndUnlabelledOnesAreRefusedByFits) {
  test::TempDir dir;
  WriteSound(dir.File("u.wav"), SF_FORMAT_WAV | SF_FORMAT_PCM_16, 10000, 1, Resonance(4000, 6));
  test::WriteFile(
      dir.File("v.csv"),
      "# hapticlab-measurement v1\n# speed_mps: 0.1\n# force_N: 1\nt_s,acc_mps2\n" + [] {
        std::string s;
        const auto x = Resonance(3000, 7);
        for (std::size_t i = 0; i < x.size(); ++i)
          s += std::to_string(static_cast<double>(i) / 2000.0) + "," + std::to_string(x[i]) + "\n";
        return s;
      }());
  const auto recs = LoadRecordings(dir.path());
  ASSERT_EQ(recs.size(), 2u);
  EXPECT_FALSE(recs[0].labelled);  // u.wav, sorted first
  EXPECT_TRUE(recs[1].labelled);
  EXPECT_EQ(recs[1].speed_mps, 0.1);
  const auto d = FirstDiagnostic([&] { FitVibrationBank(recs, {}); });
  EXPECT_EQ(d.file, dir.File("u.wav"));
  EXPECT_EQ(d.field, "speed_mps");
}

TEST(SoundRecording, RecordingsOfOneConditionArePooled) {
  // Four recordings of one AR(2) process at one condition and one at another: the bank has
  // two cells, and the pooled cell is as close to the truth as a fit of all the data as one.
  std::vector<Recording> recs;
  for (int i = 0; i < 4; ++i)
    recs.push_back({"r" + std::to_string(i), 0.1, 1.0, 2000, Resonance(3000, 20 + i, 1.0)});
  recs.push_back({"other", 0.2, 1.0, 2000, Resonance(3000, 30, 1.0)});
  VibrationFitOptions o;
  o.order = 2;
  o.band_lo_hz = 0;
  const auto bank = FitVibrationBank(recs, o);
  ASSERT_EQ(bank.cells.size(), 2u);
  const auto& pooled = bank.cells[0];
  EXPECT_EQ(pooled.speed_mps, 0.1);
  EXPECT_NEAR(pooled.coeffs[0], 1.6, 0.03);
  EXPECT_NEAR(pooled.coeffs[1], -0.9, 0.03);
  // Pooling two copies of one recording is that recording's fit.
  const auto single = FitVibrationBank({recs[0], recs[4]}, o);
  const auto twice = FitVibrationBank({recs[0], recs[0], recs[4]}, o);
  for (std::size_t k = 0; k < 2; ++k)
    EXPECT_NEAR(single.cells[0].coeffs[k], twice.cells[0].coeffs[k], 1e-12);
  // For the neural fits: joined per condition, files named.
  const auto joined = PoolByCondition(recs);
  ASSERT_EQ(joined.size(), 2u);
  EXPECT_EQ(joined[0].acc.size(), 12000u);
  EXPECT_EQ(joined[0].file, "r0 + r1 + r2 + r3");
}

}  // namespace
}  // namespace hapticlab::modeling::sound_recording_test
