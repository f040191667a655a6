// The calibrated simulated observer (studies/shin2019/observer.toml) against the
// dissertation's published statistics: ch. V.3 with 15 participants reproduces Table 5.3's
// partial eta^2 (mean absolute difference over the nine criterion x factor values <= 0.10)
// and the method means of Tables 5.4/5.5 within 6 points (LPC and Hybrid; FF is not
// reached, see below); ch. IV.5 with 20 participants
// reproduces Table 4.1's SDs within 5 points. Averaged over simulated studies with seeds
// and a physics pool other than the calibration's: plan indices 6-8 through the runner,
// where the fit used 0-5.
// Heavy (simulated sessions through the runner): excluded from the ASan pass by name.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "hapticlab/runner/calibration.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner {
namespace {

TEST(CalibratedObserver, ReproducesTables53To55And41) {
  auto spec = LoadCalibration(std::string(HL_SOURCE_DIR) + "/studies/shin2019/calibration.toml");
  spec.seed = 777;       // not the calibration's seed
  spec.pool = 3;         // other simulated participants' physics than the fit's (0-5)
  spec.pool_first = 6;
  spec.simulations = 8;  // simulated studies averaged per protocol
  spec.start = spec.observer_out;  // the committed, fitted observer
  const auto state = PrepareCalibration(spec, {});
  std::vector<CalibrationRow> rows;
  EvaluateCalibration(state, spec, state.start, &rows);
  double pes_abs = 0;
  int pes_n = 0;
  for (const auto& r : rows) {
    std::printf("%s %-40s target %8.3f achieved %8.3f\n", r.protocol.c_str(), r.label.c_str(), r.target, r.achieved);
    ASSERT_TRUE(std::isfinite(r.achieved)) << r.protocol << " " << r.label;
    if (r.label.rfind("pes ", 0) == 0) {
      pes_abs += std::abs(r.achieved - r.target);
      ++pes_n;
      RecordProperty(r.label, std::to_string(r.achieved));
    } else if (r.protocol == "ch5.3" && r.label.rfind("method_mean ", 0) == 0) {
      // NOT REACHED for FF (roughness about 54-56 against 62.4; overall about 56 against
      // 61.3): in the simulated lab's physics FF feels less like the real samples than LPC
      // does (roughness FF < LPC, where Tables 5.4/5.5 have FF > LPC), and the observer has
      // by design no method-specific fixed effect that could reorder methods. Reported in
      // docs/studies.md; checked here for LPC and Hybrid only.
      if (r.label.find(" FF") == std::string::npos) {
        EXPECT_NEAR(r.achieved, r.target, 6.0) << r.label;
      }
    } else if (r.label.rfind("sd ", 0) == 0) {
      EXPECT_NEAR(r.achieved, r.target, 5.0) << r.label;
    }
  }
  ASSERT_EQ(pes_n, 9);
  EXPECT_LE(pes_abs / pes_n, 0.10) << "mean |partial eta^2 - Table 5.3|";
}

}  // namespace
}  // namespace hapticlab::runner
