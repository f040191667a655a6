#pragma once
// Sound files for the tests that read recordings (modeling/sound_recording, apps/cmd_sound,
// apps/cmd_model_score), written with libsndfile, and the seeded noise they record.
// Header-only: hl_test_util does not link libsndfile; the tests that include this do
// (PkgConfig::SNDFILE_TEST, tests/CMakeLists.txt).

#include <gtest/gtest.h>
#include <sndfile.h>

#include <cstdint>
#include <string>
#include <vector>

namespace hapticlab::test {

/// Writes interleaved samples (`channels` per frame) as `format` (SF_FORMAT_*) at `rate_hz`;
/// a file libsndfile cannot open, or does not take whole, is a test failure.
inline void WriteSound(const std::string& path, int format, int rate_hz, int channels,
                       const std::vector<double>& data) {
  SF_INFO info{};
  info.samplerate = rate_hz;
  info.channels = channels;
  info.format = format;
  SNDFILE* f = sf_open(path.c_str(), SFM_WRITE, &info);
  ASSERT_NE(f, nullptr) << path << ": " << sf_strerror(nullptr);
  const auto frames = static_cast<sf_count_t>(data.size() / static_cast<std::size_t>(channels));
  EXPECT_EQ(sf_writef_double(f, data.data(), frames), frames) << path;
  sf_close(f);
}

/// `n` samples of the AR(2) process x[k] = c1 x[k-1] + c2 x[k-2] + gain e[k], e uniform on
/// [-0.5, 0.5) from a 64-bit LCG seeded with `seed` (Knuth's MMIX constants; no library RNG,
/// so a file's samples are the same with every standard library).
inline std::vector<double> Ar2LcgNoise(std::size_t n, std::uint64_t seed, double c1, double c2,
                                       double gain) {
  std::vector<double> x(n);
  double a1 = 0, a2 = 0;
  std::uint64_t state = seed;
  for (auto& v : x) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const double e = static_cast<double>(state >> 11) * 0x1.0p-53 - 0.5;
    v = c1 * a1 + c2 * a2 + gain * e;
    a2 = a1;
    a1 = v;
  }
  return x;
}

}  // namespace hapticlab::test
