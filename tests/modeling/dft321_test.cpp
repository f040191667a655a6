// DFT321 against its definition (Landin et al. 2010): per frequency, the reduced signal's
// magnitude is the vector sum of the axes' magnitudes and its phase that of the axes' sum.
// The reference spectra here are direct O(n^2) DFT sums, not FFTW.

#include "hapticlab/modeling/dft321.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/modeling/vibration.hpp"

namespace hapticlab::modeling::dft321_test {
namespace {

using Cx = std::complex<double>;

Cx DirectDft(const std::vector<double>& x, std::size_t k) {
  Cx s = 0;
  const double n = static_cast<double>(x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    s += x[i] * std::polar(1.0, -2 * std::numbers::pi * static_cast<double>(k * i) / n);
  return s;
}

// Three different axes: sinusoids at different frequencies, partly shared, and noise.
std::vector<std::vector<double>> Axes(std::size_t n, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<std::vector<double>> a(3, std::vector<double>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i);
    a[0][i] = std::sin(0.21 * t) + 0.3 * rng.Normal();
    a[1][i] = 0.5 * std::cos(0.21 * t + 1.0) + std::sin(0.9 * t) + 0.2 * rng.Normal();
    a[2][i] = -0.7 * std::sin(0.9 * t + 0.4) + 0.1 * rng.Normal() + 0.05;
  }
  return a;
}

class Dft321Definition : public ::testing::TestWithParam<std::size_t> {};

TEST_P(Dft321Definition, MagnitudeIsTheVectorSumAndPhaseThatOfTheSum) {
  const std::size_t n = GetParam();  // even and odd lengths
  const auto axes = Axes(n, 7 + n);
  const auto r = Dft321(axes);
  ASSERT_EQ(r.size(), n);
  double scale = 0;
  for (const auto& a : axes) scale = std::max(scale, std::abs(DirectDft(a, 0)) + 1.0);
  for (std::size_t k = 0; k <= n / 2; ++k) {
    const Cx R = DirectDft(r, k);
    double power = 0;
    Cx sum = 0;
    for (const auto& a : axes) {
      const Cx A = DirectDft(a, k);
      power += std::norm(A);
      sum += A;
    }
    EXPECT_NEAR(std::abs(R), std::sqrt(power), 1e-9 * std::max(1.0, std::sqrt(power)))
        << "bin " << k;
    if (std::abs(sum) > 1e-6 * scale) {
      const double dphi = std::arg(R * std::conj(sum));  // phase difference in (-pi, pi]
      EXPECT_NEAR(dphi, 0.0, 1e-9) << "bin " << k;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Lengths, Dft321Definition, ::testing::Values(512u, 601u));

TEST(Dft321, OneAxisComesBackUnchanged) {
  const auto axes = Axes(777, 3);
  const auto r = Dft321({axes[1]});
  for (std::size_t i = 0; i < r.size(); ++i) EXPECT_NEAR(r[i], axes[1][i], 1e-12);
}

TEST(Dft321, RefusesAxesOfDifferentLengths) {
  EXPECT_THROW(Dft321({{1, 2, 3}, {1, 2}}), PreconditionError);
  EXPECT_THROW(Dft321({}), PreconditionError);
}

// The stream form over frames much shorter than the signal: exact where the definition is
// frame-independent (one axis; equal axes give sqrt(3) x, whose spectrum is sqrt(3) X at the
// phase of 3 X), and energy preserving for different axes.
TEST(Dft321Stream, OneAxisAndEqualAxesAreExactAcrossFrames) {
  const auto axes = Axes(10007, 11);
  for (const int naxes : {1, 3}) {
    Dft321Stream s(naxes, 256);
    std::vector<double> inter;
    for (std::size_t i = 0; i < axes[0].size(); ++i)
      for (int a = 0; a < naxes; ++a) inter.push_back(axes[0][i]);
    std::vector<int> cols;
    for (int a = 0; a < naxes; ++a) cols.push_back(a);
    // In uneven blocks, as a reader delivers them.
    std::size_t done = 0;
    for (const std::size_t block : {1u, 100u, 4096u, 5810u}) {
      s.Push(inter.data() + done * static_cast<std::size_t>(naxes), block, naxes, cols.data());
      done += block;
    }
    ASSERT_EQ(done, axes[0].size());
    const auto r = s.Finish();
    ASSERT_EQ(r.size(), axes[0].size());
    const double gain = std::sqrt(static_cast<double>(naxes));
    for (std::size_t i = 0; i < r.size(); ++i) ASSERT_NEAR(r[i], gain * axes[0][i], 1e-9) << i;
  }
}

TEST(Dft321Stream, KeepsTheAxesEnergyAndPicksColumns) {
  const auto axes = Axes(60000, 5);
  // Interleaved with an unused column 0: the axes are columns 3, 1, 2.
  std::vector<double> inter;
  for (std::size_t i = 0; i < axes[0].size(); ++i)
    inter.insert(inter.end(), {99.0, axes[1][i], axes[2][i], axes[0][i]});
  const int cols[] = {3, 1, 2};
  Dft321Stream s(3, 1024);
  s.Push(inter.data(), axes[0].size(), 4, cols);
  const auto r = s.Finish();
  double er = 0, ea = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    er += r[i] * r[i];
    for (const auto& a : axes) ea += a[i] * a[i];
  }
  EXPECT_NEAR(er / ea, 1.0, 0.02);
  // Frame-wise and whole-signal reductions have the same (Welch) spectrum.
  EXPECT_LT(SpectralError(Dft321(axes), r, 512), 0.05);
}

}  // namespace
}  // namespace hapticlab::modeling::dft321_test
