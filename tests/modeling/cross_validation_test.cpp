// The ch. III.4 cross-validation loop shared by the LPC bank and the neural models
// (modeling/cross_validation.hpp), driven by stand-in models whose E_s is known.

#include "hapticlab/modeling/cross_validation.hpp"

#include <gtest/gtest.h>

#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"

namespace hapticlab::modeling::cross_validation_test {
namespace {

std::vector<Recording> Grid() {
  std::vector<Recording> recs;
  std::uint64_t k = 0;
  for (const double v : {0.04, 0.06, 0.08})
    for (const double f : {0.5, 1.0}) {
      Recording r;
      r.speed_mps = v;
      r.force_N = f;
      r.rate_hz = 2000;
      r.file = "r" + std::to_string(k);
      Rng rng(100 + k++);
      for (int i = 0; i < 4000; ++i) r.acc.push_back(rng.Normal());
      recs.push_back(r);
    }
  return recs;
}

TEST(CrossValidation, FitsOnTheTrainingConditionsAndScoresEveryRecording) {
  const auto recs = Grid();
  const VibrationFitOptions pre;
  std::vector<Recording> fitted_on;
  std::vector<std::uint64_t> seeds;
  // The stand-in model reproduces the training recordings exactly (E_s 0) and plays the
  // others at twice their amplitude (E_s exactly 1: |2 X - X| / |X|).
  const auto res = CrossValidateModel(
      recs, {0.04, 0.08}, {0.5, 1.0}, pre,
      [&](const std::vector<Recording>& train) -> ConditionSynthesizer {
        fitted_on = train;
        return [&, train](const Recording& r, std::size_t n, std::uint64_t seed) {
          seeds.push_back(seed);
          auto x = Preprocess(r, pre);
          EXPECT_EQ(x.size(), n);
          const bool seen = NearAny({train[0].speed_mps, train[3].speed_mps}, r.speed_mps);
          if (!seen)
            for (auto& v : x) v *= 2;
          return x;
        };
      },
      7);
  ASSERT_EQ(fitted_on.size(), 4u) << "the 2 x 2 training conditions";
  for (const auto& r : fitted_on) EXPECT_NE(r.speed_mps, 0.06);
  ASSERT_EQ(res.rows.size(), recs.size());
  for (std::size_t i = 0; i < recs.size(); ++i) {
    EXPECT_EQ(res.rows[i].speed_mps, recs[i].speed_mps);
    EXPECT_EQ(res.rows[i].train, recs[i].speed_mps != 0.06);
    EXPECT_NEAR(res.rows[i].es, res.rows[i].train ? 0.0 : 1.0, 1e-9);
    EXPECT_EQ(seeds[i], 7 + i) << "seed + the recording's index";
  }
  EXPECT_NEAR(res.mean_es_train, 0.0, 1e-9);
  EXPECT_NEAR(res.mean_es_test, 1.0, 1e-9);
}

TEST(CrossValidation, FewerThanThreeTrainingRecordingsIsBadInput) {
  const auto recs = Grid();
  bool fitted = false;
  try {
    CrossValidateModel(
        recs, {0.04}, {0.5, 1.0}, {},
        [&](const std::vector<Recording>&) -> ConditionSynthesizer {
          fitted = true;
          return {};
        },
        1);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("training conditions"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("found 2"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fitted);
}

}  // namespace
}  // namespace hapticlab::modeling::cross_validation_test
