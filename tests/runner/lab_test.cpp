// The lab of a session (runner/src/lab.cpp): stimulus names, and every problem of a
// protocol's model and profile files reported together with file, line and field.

#include "../../runner/src/lab.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner::internal::lab_test {
namespace {

TEST(Lab, ParseStimulusSplitsKindAndId) {
  const Stimulus real = ParseStimulus("real:Denim");
  EXPECT_TRUE(real.real);
  EXPECT_EQ(real.id, "Denim");
  const Stimulus virt = ParseStimulus("virtual:Cork");
  EXPECT_FALSE(virt.real);
  EXPECT_EQ(virt.id, "Cork");
  // An id may itself hold a colon: only the first one separates the kind.
  EXPECT_EQ(ParseStimulus("virtual:a:b").id, "a:b");
  // "realistic:X" is not a real stimulus; a bare id is virtual.
  EXPECT_FALSE(ParseStimulus("realistic:X").real);
  EXPECT_FALSE(ParseStimulus("Denim").real);
  EXPECT_EQ(ParseStimulus("Denim").id, "Denim");
}

TEST(Lab, EveryPhaseHasItsRecordedName) {
  using protocols::PhaseKind;
  for (const PhaseKind k : {PhaseKind::kTraining, PhaseKind::kReference, PhaseKind::kMain,
                            PhaseKind::kStaircase, PhaseKind::kQuestPlus}) {
    EXPECT_EQ(NameOf(kPhaseKindNames, k), protocols::ToString(k));
    EXPECT_EQ(FromName(kPhaseKindNames, protocols::ToString(k)), k);
    EXPECT_EQ(IsTraining(k), k == PhaseKind::kTraining);
  }
  EXPECT_EQ(FromName(kPhaseKindNames, "Training"), std::nullopt);  // a name no phase has
}

TEST(Lab, LoadsEveryPlaceholderModelFromItsProfile) {
  const auto p = protocols::LoadProtocol(test::DataPath("protocols/small.toml"));
  const Lab lab = LoadLab(p, "sim");
  EXPECT_EQ(lab.protocol, &p);
  ASSERT_EQ(lab.models.size(), p.materials.size());
  for (const auto& m : p.materials) {
    EXPECT_EQ(lab.models.count(m.id), 1u) << m.id;
    EXPECT_EQ(lab.model_hashes.at(m.id).size(), 64u) << m.id;  // SHA-256, hex
  }
}

TEST(Lab, ReportsEveryMissingFileTogetherNamingTheProtocol) {
  test::TempDir dir;
  std::string text = test::ReadFile(test::DataPath("protocols/small.toml"));
  text.replace(text.find("profiles = \"profiles.toml\""), 26, "profiles = \"nowhere.toml\"");
  text.replace(text.find("id = \"Denim\""), 12, "id = \"Denim\"\nmodel = \"denim.toml\"");
  const std::string path = dir.File("p.toml");
  std::ofstream(path) << text;
  const auto p = protocols::LoadProtocol(path);
  try {
    (void)LoadLab(p, "sim");
    FAIL() << "no error";
  } catch (const InputError& e) {
    bool profiles = false, model = false;
    for (const auto& d : e.diagnostics()) {
      EXPECT_EQ(d.file, path);
      profiles |=
          d.field == "study.profiles" && d.message.find("nowhere.toml") != std::string::npos;
      model |= d.field == "material.model" && d.message.find("denim.toml") != std::string::npos &&
               d.line > 0;
    }
    EXPECT_TRUE(profiles) << e.what();
    EXPECT_TRUE(model) << e.what();
  }
}

}  // namespace
}  // namespace hapticlab::runner::internal::lab_test
