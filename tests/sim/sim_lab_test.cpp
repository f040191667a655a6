// The simulated observer's variance structure (sim::Observer::RateDistance) and its file
// (sim::LoadObserver): each random effect shows up with the SD the file gives it, and a bad
// file is refused with file:line: key.

#include "hapticlab/sim/sim_lab.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::sim::sim_lab_test {
namespace {

ObserverParams Quiet() {
  ObserverParams p;
  p.defaults = {.sensitivity = 1, .offset_sd = 0, .material_sd = 0, .method_sd = 0, .noise_sd = 0};
  return p;
}

// SD over many participants of (rating of a - rating of b), everything else equal.
double SdOfDifference(const ObserverParams& p, const std::string& ma, const std::string& mb,
                      const std::string& ka, const std::string& kb) {
  double s = 0, s2 = 0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const Observer o(p, 1000 + static_cast<std::uint64_t>(i), {"roughness"});
    Rng r1(5), r2(5);
    const double d = o.RateDistance("roughness", ma, ka, 1.0, -1e6, 1e6, r1) -
                     o.RateDistance("roughness", mb, kb, 1.0, -1e6, 1e6, r2);
    s += d;
    s2 += d * d;
  }
  return std::sqrt(s2 / n - (s / n) * (s / n));
}

TEST(Observer, RandomEffectsHaveTheirSds) {
  auto p = Quiet();
  p.defaults.material_sd = 6;
  // Two materials: the difference has SD sqrt(2) x 6; the same material: none.
  EXPECT_NEAR(SdOfDifference(p, "Denim", "Cork", "LPC", "LPC"), std::sqrt(2.0) * 6, 0.4);
  EXPECT_NEAR(SdOfDifference(p, "Denim", "Denim", "LPC", "FF"), 0, 1e-12);
  p = Quiet();
  p.criteria["roughness"] = {
      .sensitivity = 1, .offset_sd = 0, .material_sd = 0, .method_sd = 4, .noise_sd = 0};
  EXPECT_NEAR(SdOfDifference(p, "Denim", "Denim", "LPC", "FF"), std::sqrt(2.0) * 4, 0.3);
  EXPECT_NEAR(SdOfDifference(p, "Denim", "Cork", "LPC", "LPC"), 0, 1e-12);
}

// A site offset (study run --site-offset, study power --site-sd) moves every rating of the
// observer by exactly that many points, the same draws otherwise; clamped at the scale's ends.
TEST(Observer, SiteOffsetShiftsEveryRating) {
  auto p = ObserverParams{};
  auto shifted = p;
  shifted.site_offset = 6.5;
  const Observer a(p, 77, {"roughness"}), b(shifted, 77, {"roughness"});
  for (double d : {0.0, 0.7, 2.0}) {
    Rng r1(9), r2(9);
    EXPECT_NEAR(b.RateDistance("roughness", "Denim", "FF", d, -1e6, 1e6, r2) -
                    a.RateDistance("roughness", "Denim", "FF", d, -1e6, 1e6, r1),
                6.5, 1e-9);
  }
  shifted.site_offset = 500;
  const Observer c(shifted, 77, {"roughness"});
  Rng r3(9);
  EXPECT_EQ(c.RateDistance("roughness", "Denim", "FF", 0.5, 0, 100, r3), 100);
}

TEST(Observer, ScaleRangeOffsetNoiseAndLapses) {
  auto p = Quiet();
  p.range_sd = 0.3;
  p.defaults.offset_sd = 5;
  // Latent at d = 0 is upper (78); mid = 50: rating = 50 + r 28 + o. Over participants:
  // mean 50 + 28 exp(0.045), SD^2 = 28^2 Var(r) + 25 with Var(r) = (e^0.09 - 1) e^0.09.
  double s = 0, s2 = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const Observer o(p, 77 + static_cast<std::uint64_t>(i), {"overall"});
    Rng r(3);
    const double y =
        o.RateDistance("overall", "A", "B", 0.0, -1000, 1100, r);  // mid 50, never clamped
    s += y;
    s2 += y * y;
  }
  const double mean = s / n, sd = std::sqrt(s2 / n - mean * mean);
  EXPECT_NEAR(mean, 50 + 28 * std::exp(0.045), 0.3);
  EXPECT_NEAR(sd, std::sqrt(28.0 * 28 * (std::exp(0.09) - 1) * std::exp(0.09) + 25), 0.3);
  // Trial noise and lapses within one participant.
  p = Quiet();
  p.defaults.noise_sd = 7;
  p.lapse_rate = 0.1;
  const Observer o(p, 9, {"overall"});
  Rng r(11);
  int far = 0;
  double ns = 0, ns2 = 0;
  int nn = 0;
  for (int i = 0; i < n; ++i) {
    const double y = o.RateDistance("overall", "A", "B", 0.0, 0, 100, r);
    if (std::abs(y - 78) > 35)
      ++far;  // 5 noise SDs: only a lapse lands there
    else {
      ns += y;
      ns2 += y * y;
      ++nn;
    }
  }
  // Lapses are uniform on [0, 100]; those below 43 (a fraction 0.43 of them) land outside
  // 78 +- 35, which the noise alone (5 SDs) practically never reaches.
  EXPECT_NEAR(static_cast<double>(far) / n, 0.1 * 0.43, 0.006);
  EXPECT_GT(std::sqrt(ns2 / nn - (ns / nn) * (ns / nn)), 6.5);  // at least the trial noise (SD 7)
}

TEST(Observer, FileErrorsNameFileLineAndKey) {
  test::TempDir dir;
  const std::string f = dir.File("observer.toml");
  test::WriteFile(f,
                  "[observer]\nupper = 78\nnoise_sd = -1\nrange_sdd = "
                  "0.2\n\n[criterion.roughness]\nsensitivity = 1\nmethod_sd = \"x\"\n");
  try {
    LoadObserver(f);
    FAIL() << "accepted a bad observer file";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(f + ":3: observer.noise_sd"), std::string::npos) << m;
    EXPECT_NE(m.find(f + ":4: observer.range_sdd"), std::string::npos) << m;
    EXPECT_NE(m.find(f + ":8: criterion.roughness.method_sd"), std::string::npos) << m;
  }
  test::WriteFile(f, "[observer]\nnoise_sd = 9\n[criterion.friction]\nmethod_sd = 3\n");
  const auto p = LoadObserver(f);
  EXPECT_EQ(p.For("friction").method_sd, 3);
  EXPECT_EQ(p.For("friction").noise_sd, 9);  // the default, inherited
  EXPECT_EQ(p.For("overall").noise_sd, 9);
}

TEST(Observer, ShippedObserverFileLoads) {
  const auto p = LoadObserver(std::string(HL_SOURCE_DIR) + "/studies/shin2019/observer.toml");
  EXPECT_GT(p.upper, p.lower);
}

}  // namespace
}  // namespace hapticlab::sim::sim_lab_test
