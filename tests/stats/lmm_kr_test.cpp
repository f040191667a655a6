// Kenward-Roger small-sample inference (lmm_kr.cpp) against pbkrtest 0.5.2 via lmerTest
// 3.1.3 (tests/data/stats/lmm_reference.json, made by tests/data/stats/lmm_reference.R).

#include <gtest/gtest.h>

#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/lmm.hpp"
#include "lmm_reference.hpp"

namespace hapticlab::stats::lmm_kr_test {
namespace {

using lmm_reference::ExpectClose;
using lmm_reference::Load;
using lmm_reference::Ref;
using nlohmann::json;

// Kenward-Roger (REML fits): adjusted SEs, df, t, p; scaled F, df, p (pbkrtest via lmerTest).
void CompareKenwardRoger(const std::string& design,
                         const std::string& file = "stats/lmm_reference.json") {
  const json ref = Ref(design, file);
  ASSERT_FALSE(ref.is_null()) << design;
  const json& w = ref["reml"]["kr"];
  LmmOptions o;
  o.kenward_roger = true;
  const auto r = FitLmm(Load(ref), ref["formula"].get<std::string>(), o);
  EXPECT_EQ(r.ddf, "Kenward-Roger");
  ASSERT_EQ(r.fixed.size(), w["fixed"].size());
  for (std::size_t i = 0; i < r.fixed.size(); ++i) {
    const auto& c = r.fixed[i];
    const auto& e = w["fixed"][i];
    const std::string name = design + " KR " + e["name"].get<std::string>();
    ExpectClose(c.se, e["se"], name + " se");
    ExpectClose(c.df, e["df"], name + " df");
    ExpectClose(c.t, e["t"], name + " t", 1.0);
    ExpectClose(c.p, e["p"], name + " p");
  }
  ASSERT_EQ(r.anova.size(), w["anova"].size());
  for (std::size_t i = 0; i < r.anova.size(); ++i) {
    const std::string name = design + " KR " + w["anova"][i]["term"].get<std::string>();
    ExpectClose(r.anova[i].den_df, w["anova"][i]["den_df"], name + " den df");
    ExpectClose(r.anova[i].F, w["anova"][i]["F"], name + " F");
    ExpectClose(r.anova[i].p, w["anova"][i]["p"], name + " p");
  }
}

TEST(Lmm, CrossedRandomSlopesKenwardRoger) { CompareKenwardRoger("crossed"); }
TEST(Lmm, UnbalancedNumericSlopeKenwardRoger) { CompareKenwardRoger("unbalanced"); }
TEST(Lmm, SingularFitKenwardRoger) { CompareKenwardRoger("singular"); }

TEST(Lmm, KenwardRogerNeedsReml) {
  const json ref = Ref("singular");
  LmmOptions o;
  o.kenward_roger = true;
  o.reml = false;
  EXPECT_THROW(FitLmm(Load(ref), ref["formula"].get<std::string>(), o), InputError);
}

}  // namespace
}  // namespace hapticlab::stats::lmm_kr_test
