#pragma once
// A one-factor long table (subject, cond, y) for the ANOVA and Tukey tests.

#include <string>
#include <tuple>
#include <vector>

#include "hapticlab/stats/long_table.hpp"

namespace hapticlab::stats::fixture {

inline LongTable Make(const std::vector<std::tuple<std::string, std::string, double>>& rows) {
  LongTable t;
  t.key_names = {"subject", "cond"};
  t.keys.assign(2, {});
  for (const auto& [s, c, y] : rows) {
    t.keys[0].push_back(s);
    t.keys[1].push_back(c);
    t.y.push_back(y);
  }
  return t;
}

}  // namespace hapticlab::stats::fixture
