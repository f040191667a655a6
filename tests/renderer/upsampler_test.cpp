// Band-limited polyphase upsampling: the ideal interpolation of a sampled sine below the input's
// Nyquist frequency is that sine itself (Shannon), so the output is compared with it.

#include "hapticlab/renderer/upsampler.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "hapticlab/core/status.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::renderer::upsampler_test {
namespace {

constexpr double kPi = std::numbers::pi;

// Upsamples sin(2 pi f k / fs_in) by L; returns the output after the filter has filled.
std::vector<double> UpsampleSine(PolyphaseUpsampler& up, double f_over_fin, int inputs) {
  std::vector<double> y;
  const int L = up.factor();
  for (int k = 0; k < inputs; ++k) {
    up.Push(std::sin(2 * kPi * f_over_fin * k));
    for (int p = 0; p < L; ++p) y.push_back(up.Output(p));
  }
  return {y.begin() + 100 * L, y.end()};
}

// Amplitude of the component at f (cycles per output sample) by correlation over whole periods.
double Amplitude(const std::vector<double>& y, double f) {
  std::complex<double> s(0, 0);
  for (std::size_t n = 0; n < y.size(); ++n)
    s += y[n] * std::polar(1.0, -2 * kPi * f * static_cast<double>(n));
  return 2 * std::abs(s) / static_cast<double>(y.size());
}

TEST(Upsampler, ReproducesSinesInThePassBandWithTheStatedDelay) {
  PolyphaseUpsampler up(10, 32);
  for (double f : {0.05, 0.2, 0.35, 0.45}) {
    up.Reset();
    const auto y = UpsampleSine(up, f, 2100);
    // y[n] (n counted from input 100) = sin(2 pi f (n / L + 100 - delay)).
    double err = 0;
    for (std::size_t n = 0; n < y.size(); ++n) {
      const double t_in = static_cast<double>(n) / 10 + 100 - up.DelayInputSamples();
      err = std::max(err, std::abs(y[n] - std::sin(2 * kPi * f * t_in)));
    }
    EXPECT_LT(err, f < 0.4 ? 2e-3 : 1e-2) << "f = " << f << " f_in";
  }
}

TEST(Upsampler, SuppressesImagesWhereLinearInterpolationLeavesThem) {
  // A tone at 0.45 f_in: its first image lies at 0.55 f_in. 2000 inputs = 900 whole periods.
  PolyphaseUpsampler up(10, 32);
  const auto y = UpsampleSine(up, 0.45, 2100);
  const double tone = Amplitude(y, 0.045), image = Amplitude(y, 0.055);
  EXPECT_NEAR(20 * std::log10(tone), 0.0, 0.1);  // pass band
  EXPECT_LT(20 * std::log10(image / tone), -40.0);
  // Linear interpolation of the same input (the renderer's former upsampling) for contrast:
  // sinc^2: -3.1 dB at the tone, and its image at 0.55 f_in only 3.5 dB below the tone.
  std::vector<double> lin;
  double prev = 0;
  for (int k = 0; k < 2100; ++k) {
    const double x = std::sin(2 * kPi * 0.45 * k);
    for (int p = 0; p < 10; ++p) lin.push_back(prev + (x - prev) * (p + 1) / 10.0);
    prev = x;
  }
  lin.erase(lin.begin(), lin.begin() + 1000);
  EXPECT_LT(20 * std::log10(Amplitude(lin, 0.045)), -2.5);
  EXPECT_GT(20 * std::log10(Amplitude(lin, 0.055) / Amplitude(lin, 0.045)), -30.0);
}

TEST(Upsampler, FactorOnePassesThroughAndOutputsAllocateNothing) {
  PolyphaseUpsampler one(1, 32);
  one.Push(0.25);
  EXPECT_EQ(one.Output(0), 0.25);
  EXPECT_EQ(one.DelayInputSamples(), 0.0);
  EXPECT_THROW(PolyphaseUpsampler(0, 8), PreconditionError);
  PolyphaseUpsampler up(5, 32);
  double s = 0;
  {
    test::NoAllocGuard guard;
    for (int k = 0; k < 1000; ++k) {
      up.Push(k % 7 - 3.0);
      for (int p = 0; p < 5; ++p) s += up.Output(p);
    }
    EXPECT_EQ(guard.count(), 0u);
  }
  EXPECT_TRUE(std::isfinite(s));
}

}  // namespace
}  // namespace hapticlab::renderer::upsampler_test
