#include "hapticlab/renderer/biquad.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "hapticlab/core/status.hpp"

namespace hapticlab::renderer::biquad_test {
namespace {

// Amplitude of a filtered sine after its transient has died out.
double MeasuredGain(BiquadCoeffs c, double f, double fs) {
  Biquad b(c);
  double peak = 0;
  const int n = static_cast<int>(fs * 2);
  for (int i = 0; i < n; ++i) {
    const double y = b.Step(std::sin(2 * std::numbers::pi * f * i / fs));
    if (i > n / 2) peak = std::max(peak, std::abs(y));
  }
  return peak;
}

TEST(Biquad, ButterworthMinus3dBAtCutoff) {
  const double m3db = 1.0 / std::sqrt(2.0);
  for (double fs : {1000.0, 4000.0, 10000.0, 20000.0}) {
    for (double fc : {50.0, 100.0, 150.0}) {
      const auto lp = BiquadCoeffs::ButterworthLowPass(fc, fs);
      const auto hp = BiquadCoeffs::ButterworthHighPass(fc, fs);
      EXPECT_NEAR(lp.Magnitude(fc, fs), m3db, 1e-9);
      EXPECT_NEAR(hp.Magnitude(fc, fs), m3db, 1e-9);
      EXPECT_NEAR(lp.Magnitude(0, fs), 1.0, 1e-12);
      EXPECT_NEAR(hp.Magnitude(fs / 2, fs), 1.0, 1e-9);
      // The running filter has the designed gain (time-domain check of the recursion).
      EXPECT_NEAR(MeasuredGain(lp, fc, fs), m3db, 5e-3);
      EXPECT_NEAR(MeasuredGain(hp, fc, fs), m3db, 5e-3);
    }
  }
}

TEST(Biquad, RejectsCutoffAboveNyquist) {
  EXPECT_THROW(BiquadCoeffs::ButterworthLowPass(600, 1000), PreconditionError);
  EXPECT_THROW(BiquadCoeffs::ButterworthHighPass(0, 1000), PreconditionError);
}

}  // namespace
}  // namespace hapticlab::renderer::biquad_test
