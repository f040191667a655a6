// PlanToJson (runner/src/plan_json.cpp): the plan's one JSON form, shared by
// `study plan --json` and the session provenance.
#include "hapticlab/runner/plan_json.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner::plan_json_test {
namespace {

TEST(PlanJson, EqualsTheGoldenPlanTheCliWrote) {
  // small_plan_p3.json was written by `hapticlab study plan small.toml --index 3 --json`
  // (tests/protocols/plan_test.cpp checks it against Plan field by field).
  const auto p = protocols::LoadProtocol(test::DataPath("protocols/small.toml"));
  std::ifstream f(test::DataPath("protocols/small_plan_p3.json"));
  const auto golden = nlohmann::json::parse(f);
  const nlohmann::json j = PlanToJson(protocols::Plan(p, 3));
  ASSERT_EQ(j.size(), golden["trials"].size());
  for (std::size_t i = 0; i < j.size(); ++i) EXPECT_EQ(j[i], golden["trials"][i]) << "trial " << i;
}

TEST(PlanJson, NumbersTrialsFromOneAndKeepsThePlanIndex) {
  protocols::PlannedTrial t;
  t.index = 4;
  t.material = "Denim";
  t.break_before = true;
  const nlohmann::json j = PlanToJson({t});
  ASSERT_EQ(j.size(), 1U);
  EXPECT_EQ(j[0]["trial"], 5);
  EXPECT_EQ(j[0]["plan_index"], 4);
  EXPECT_EQ(j[0]["material"], "Denim");
  EXPECT_EQ(j[0]["break_before"], true);
  EXPECT_TRUE(PlanToJson({}).is_array());
  EXPECT_TRUE(PlanToJson({}).empty());
}

}  // namespace
}  // namespace hapticlab::runner::plan_json_test
