// The neural model's synthesis (renderer/src/neural.cpp): allocation-free, deterministic and silent
// out of contact; Γ_U's per-cell AR part mixed as the LPC bank mixes (against a closed-form AR(2)
// LSF reference); power-complementary band crossovers. Models come from the fit (modeling).

#include <gtest/gtest.h>

#include "../modeling/neural_fixture.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::modeling::neural_test {
namespace {

TEST(Neural, SynthesisIsAllocationFreeDeterministicAndSilentOutOfContact) {
  for (const int variant : {0, 1, 2}) {  // Γ_U, Γ_U with per-cell AR fits, Γ_D
    const auto t =
        variant < 2 ? renderer::NeuralTopology::kUnified : renderer::NeuralTopology::kDecomposed;
    auto m = std::make_shared<renderer::NeuralModel>(SmallModel(t, variant == 1));
    // With per-cell AR fits Γ_U's linear part is the AR bank mixed at every new condition
    // (LSF interpolation inside Step): the guard covers it.
    EXPECT_EQ(!m->bands[0].cell_ar.empty(), variant == 1);
    renderer::NeuralSynth a(m, 9), b(m, 9);
    std::vector<double> xa(4000), xb(4000);
    auto force_N = [](std::size_t k) { return 0.6 + 1.2 * static_cast<double>(k % 700) / 700.0; };
    {
      test::NoAllocGuard guard;
      for (std::size_t k = 0; k < xa.size(); ++k) {
        const double v = 0.04 + 0.08 * static_cast<double>(k) / 4000.0;
        xa[k] = a.Step(v, force_N(k), true);
      }
      EXPECT_EQ(guard.count(), 0u);
    }
    for (std::size_t k = 0; k < xb.size(); ++k)
      xb[k] = b.Step(0.04 + 0.08 * static_cast<double>(k) / 4000.0, force_N(k), true);
    EXPECT_EQ(xa, xb);
    double p = 0;
    for (const double x : xa) {
      ASSERT_TRUE(std::isfinite(x));
      p += x * x;
    }
    EXPECT_GT(p, 0);
    EXPECT_EQ(a.Step(0.08, 1.0, false), 0.0);  // out of contact
    EXPECT_EQ(a.Step(0.005, 1.0, true), 0.0);  // below the minimum speed
  }
}

// Γ_U's linear part between the training cells is the LPC bank's interpolation: the cells'
// LSFs mixed with the grid's bilinear weights. Reference written independently of the
// renderer's LSF code: for an AR(2), A(z) = 1 + a1 z^-1 + a2 z^-2, P(z) = (1 + z^-1)
// (1 + (a1 + a2 - 1) z^-1 + z^-2) and Q(z) = (1 - z^-1)(1 + (a1 - a2 + 1) z^-1 + z^-2), so its
// two LSFs have cos w_p = (1 - a1 - a2) / 2 and cos w_q = -(1 + a1 - a2) / 2. A one-band Γ_U
// model with a silent network is then exactly that AR process (same noise, the band's 10 Hz
// drift high-pass at the output).
TEST(Neural, UnifiedLinearPartIsTheLpcBanksLsfInterpolation) {
  auto m = std::make_shared<renderer::NeuralModel>();
  m->speeds_mps = {0.04, 0.12};
  m->forces_N = {0.5, 1.5};
  renderer::NeuralBand band;
  band.lo_hz = 20;
  band.hi_hz = 1000;
  band.decimation = 1;
  band.history = 2;
  renderer::NeuralNet net;
  net.layers = {4, 1};
  net.params.assign(net.ParamCount(), 0.0);
  band.nets = {net};
  band.sigma.assign(4, 0.1);
  auto resonance = [](double f_hz, double r) {  // c = (2 r cos w, -r^2)
    return std::vector<double>{2 * r * std::cos(2 * kPi * f_hz / 2000), -r * r};
  };
  band.cell_ar = {resonance(150, 0.95), resonance(250, 0.9), resonance(450, 0.9),
                  resonance(700, 0.8)};  // (4 cm/s, 0.5 N), (4, 1.5), (12, 0.5), (12, 1.5)
  m->bands = {band};
  renderer::NeuralSynth synth(m, 5);
  Rng noise(5);
  renderer::Biquad hp(renderer::BiquadCoeffs::ButterworthHighPass(10, 2000));
  double y1 = 0, y2 = 0, worst = 0, power = 0, coeff_gap = 0;
  for (int k = 0; k < 6000; ++k) {
    const double v = k < 2000 ? 0.06 : k < 4000 ? 0.09 : 0.11, f = k < 3000 ? 0.8 : 1.2;
    const double tv = (v - 0.04) / 0.08, tf = (f - 0.5) / 1.0;
    const double w[4] = {(1 - tv) * (1 - tf), (1 - tv) * tf, tv * (1 - tf), tv * tf};
    double cp = 0, cq = 0, mean1 = 0, mean2 = 0;  // mixed cos of the LSFs; naive mixing
    for (int c = 0; c < 4; ++c) {
      const double a1 = -band.cell_ar[static_cast<std::size_t>(c)][0],
                   a2 = -band.cell_ar[static_cast<std::size_t>(c)][1];
      cp += w[c] * std::acos((1 - a1 - a2) / 2);
      cq += w[c] * std::acos(-(1 + a1 - a2) / 2);
      mean1 += w[c] * band.cell_ar[static_cast<std::size_t>(c)][0];
      mean2 += w[c] * band.cell_ar[static_cast<std::size_t>(c)][1];
    }
    // Back from the mixed LSFs: a1 + a2 = 1 - 2 cos w_p, a1 - a2 = -1 - 2 cos w_q.
    const double s = 1 - 2 * std::cos(cp), d = -1 - 2 * std::cos(cq);
    const double c1 = -(s + d) / 2, c2 = -(s - d) / 2;
    coeff_gap = std::max(coeff_gap, std::abs(c1 - mean1) + std::abs(c2 - mean2));
    const double y = c1 * y1 + c2 * y2 + 0.1 * noise.Normal();
    y2 = y1;
    y1 = y;
    const double want = hp.Step(y), got = synth.Step(v, f, true);
    worst = std::max(worst, std::abs(got - want));
    power += want * want;
  }
  const double rms = std::sqrt(power / 6000);
  EXPECT_GT(rms, 0.05);
  EXPECT_LT(worst, 1e-9 * rms) << "Γ_U's linear part is not the LSF interpolation";
  // The check can fail: mixing the coefficients instead of the LSFs gives other filters here.
  EXPECT_GT(coeff_gap, 0.01);
}

// The crossovers that select each band at synthesis (docs/modeling-neural.md): every band's
// network runs on a signal that covers its whole decimated range, and band b's output passes
// the fourth-order Butterworth high-passes of the boundaries below it and the low-pass at its
// top. The bands are independent processes, so their powers add: with every network silent
// and each band driven by white noise of the density of a white 2 kHz signal (scale 1/sqrt(γ)),
// the sum must be white over 20-950 Hz (power-complementary crossovers, the interpolators'
// roll-off included). Without the crossovers bands 3 and 4 would each add a full-range white
// signal (+3 dB over 0-1000 Hz), with amplitude-complementary (Linkwitz-Riley) ones the sum
// would lose 3 dB at every boundary.
TEST(Neural, BandCrossoversArePowerComplementary) {
  auto m = std::make_shared<renderer::NeuralModel>();
  m->topology = renderer::NeuralTopology::kDecomposed;
  m->speeds_mps = {0.05};
  m->forces_N = {1.0};
  m->bands = renderer::DefaultNeuralBands();
  for (auto& b : m->bands) {
    renderer::NeuralNet n;
    n.layers = {b.history, 1};
    n.params.assign(n.ParamCount(), 0.0);  // silent network: the band is its white excitation
    b.nets = {n};
    b.sigma = {1.0};
    b.scale = 1 / std::sqrt(static_cast<double>(b.decimation));
  }
  renderer::NeuralSynth s(m, 17);
  std::vector<double> x(200000);
  for (std::size_t k = 0; k < 4000; ++k) s.Step(0.05, 1.0, true);
  for (auto& v : x) v = s.Step(0.05, 1.0, true);
  const int seg = 512;
  const auto mag = WelchMagnitude(x, seg);
  const double white = std::sqrt(3.0 * seg / 8.0);  // E|X_k|^2 of unit white noise, Hann window
  double worst_db = 0, worst_hz = 0;
  for (std::size_t k = 0; k + 4 < mag.size(); k += 4) {  // 4-bin (15.6 Hz) averages of the power
    const double f0 = static_cast<double>(k) * 2000.0 / seg;
    if (f0 < 20 || f0 + 15.6 > 950) continue;
    double p = 0;
    for (std::size_t j = k; j < k + 4; ++j) p += mag[j] * mag[j];
    const double db = 10 * std::log10(p / 4 / (white * white));
    if (std::abs(db) > std::abs(worst_db)) worst_db = db, worst_hz = f0;
  }
  std::printf(
      "sum of the silent bands: largest departure from white %.2f dB at %.0f Hz (20-950 Hz)\n",
      worst_db, worst_hz);
  EXPECT_LT(std::abs(worst_db), 0.75) << "at " << worst_hz << " Hz";
}
}  // namespace
}  // namespace hapticlab::modeling::neural_test
