#include "hapticlab/renderer/biquad.hpp"

#include <complex>
#include <stdexcept>

#include "hapticlab/core/status.hpp"

namespace hapticlab::renderer {
namespace {

void Check(double fc, double fs) {
  HL_REQUIRE(fs > 0 && fc > 0 && fc < fs / 2,
             "biquad cut-off must lie in (0, fs/2); got fc=" + std::to_string(fc) +
                 " Hz, fs=" + std::to_string(fs) + " Hz");
}

}  // namespace

// Bilinear transform of the analog prototype 1/(s^2 + sqrt(2) s + 1), with K = tan(pi fc/fs)
// pre-warping the cut-off so the -3 dB point lands exactly at fc.
BiquadCoeffs BiquadCoeffs::ButterworthLowPass(double fc, double fs) {
  Check(fc, fs);
  const double k = std::tan(std::numbers::pi * fc / fs);
  const double q = std::numbers::sqrt2;
  const double norm = 1.0 / (1.0 + q * k + k * k);
  BiquadCoeffs c;
  c.b0 = k * k * norm;
  c.b1 = 2.0 * c.b0;
  c.b2 = c.b0;
  c.a1 = 2.0 * (k * k - 1.0) * norm;
  c.a2 = (1.0 - q * k + k * k) * norm;
  return c;
}

BiquadCoeffs BiquadCoeffs::ButterworthHighPass(double fc, double fs) {
  Check(fc, fs);
  const double k = std::tan(std::numbers::pi * fc / fs);
  const double q = std::numbers::sqrt2;
  const double norm = 1.0 / (1.0 + q * k + k * k);
  BiquadCoeffs c;
  c.b0 = norm;
  c.b1 = -2.0 * norm;
  c.b2 = norm;
  c.a1 = 2.0 * (k * k - 1.0) * norm;
  c.a2 = (1.0 - q * k + k * k) * norm;
  return c;
}

double BiquadCoeffs::Magnitude(double f_hz, double fs) const {
  const std::complex<double> z1 = std::polar(1.0, -2.0 * std::numbers::pi * f_hz / fs);
  const std::complex<double> z2 = z1 * z1;
  return std::abs((b0 + b1 * z1 + b2 * z2) / (1.0 + a1 * z1 + a2 * z2));
}

}  // namespace hapticlab::renderer
