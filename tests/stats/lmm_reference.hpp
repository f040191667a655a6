// The lme4 / lmerTest reference values (tests/data/stats/lmm_reference.json) and their
// comparison, shared by lmm_test.cpp and lmm_kr_test.cpp.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "hapticlab/stats/lmm.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::lmm_reference {

using nlohmann::json;
inline constexpr double kRel = 1e-4;

inline json Ref(const std::string& design) {
  std::ifstream f(test::DataPath("stats/lmm_reference.json"));
  return json::parse(f)[design];
}

// Relative agreement, with an absolute floor `scale` * kRel for values near zero.
inline void ExpectClose(double got, const json& want, const std::string& what, double scale = 0) {
  ASSERT_FALSE(want.is_null()) << what;
  const double w = want.get<double>();
  EXPECT_NEAR(got, w, kRel * std::max(std::abs(w), scale)) << what;
}

inline LongTable Load(const json& ref) {
  const auto f = ParseLmmFormula(ref["formula"].get<std::string>());
  auto cols = f.Columns();
  cols.erase(cols.begin());
  return ReadLongCsv(test::DataPath("stats/" + ref["csv"].get<std::string>()), f.response, cols);
}

}  // namespace hapticlab::stats::lmm_reference
