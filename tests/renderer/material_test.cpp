#include "hapticlab/renderer/material.hpp"

#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/renderer/material_keys.hpp"
#include "hapticlab/test/doc_block.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::renderer::material_test {
namespace {

constexpr const char* kGood = R"(name = "Denim"
effects = ["coulomb", "viscous", "dahl", "hc-damping"]

[contact]
texture_K = 800.0
texture_B = 2.0
texture_n = 1.2
base_model = "linear"
base_K = 1500.0

[friction]
kappa_N_per_m = 2500.0
mu_k = 0.35
mu_b_Ns_per_m = 0.4

[geometry]
kind = "sine"
amplitude_m = 2e-5
wavelength_m = 1e-3

[hybrid]
cutoff_hz = 90

[vibration]
sample_rate_hz = 2000
speeds_mps = [0.04, 0.08]
forces_N = [0.5, 1.5]

[[vibration.cells]]
speed_mps = 0.04
force_N = 0.5
ar = [0.5, -0.2]
variance = 0.1

[[vibration.cells]]
speed_mps = 0.04
force_N = 1.5
ar = [0.6, -0.25]
variance = 0.2

[[vibration.cells]]
speed_mps = 0.08
force_N = 0.5
ar = [0.4, -0.1]
variance = 0.3

[[vibration.cells]]
speed_mps = 0.08
force_N = 1.5
ar = [0.7, -0.3]
variance = 0.4
)";

TEST(Material, ParsesAFullModel) {
  const auto m = ParseMaterial(kGood, "denim.toml");
  EXPECT_EQ(m.name, "Denim");
  EXPECT_EQ(m.effects.size(), 4u);
  EXPECT_DOUBLE_EQ(m.contact.texture.n, 1.2);
  EXPECT_DOUBLE_EQ(m.friction.mu_b_Ns_per_m, 0.4);
  EXPECT_DOUBLE_EQ(m.hybrid_cutoff_hz, 90);
  ASSERT_EQ(m.vibration.cells.size(), 4u);
  EXPECT_EQ(m.vibration.cells[3].lsf.size(), 2u);
  EXPECT_NEAR(m.geometry->max_m() - m.geometry->min_m(), 4e-5, 1e-9);
}

TEST(Material, ReportsEveryProblemWithLineAndKey) {
  std::string bad = kGood;
  bad.replace(bad.find("texture_n = 1.2"), 15, "texture_n = 2.5");
  bad.replace(bad.find("mu_k = 0.35"), 11, "mu_k = \"x\"");
  bad.replace(bad.find("ar = [0.7, -0.3]"), 16, "ar = [2.0, -1.0]");  // unit-circle double pole
  bad.replace(bad.find("cutoff_hz = 90"), 14, "cutof_hz = 90");
  try {
    ParseMaterial(bad, "bad.toml");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("bad.toml:13: friction.mu_k: expected a number"), std::string::npos) << msg;
    EXPECT_NE(msg.find("vibration.cells[3].ar: unstable"), std::string::npos) << msg;
    EXPECT_NE(msg.find("hybrid.cutof_hz: unknown key"), std::string::npos) << msg;
    EXPECT_NE(msg.find("hybrid.cutoff_hz: missing"), std::string::npos) << msg;
    EXPECT_GE(e.diagnostics().size(), 4u);
  }
  // Range checks run once parsing succeeded.
  std::string range = kGood;
  range.replace(range.find("texture_n = 1.2"), 15, "texture_n = 2.5");
  try {
    ParseMaterial(range, "range.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(
        std::string(e.what()).find("range.toml:7: contact.texture_n: expected a number in [1, "
                                   "2], got 2.5"),
        std::string::npos)
        << e.what();
  }
}

TEST(Material, StoredLsfsMustMatchTheCoefficients) {
  std::string text = kGood;
  text.replace(text.find("ar = [0.5, -0.2]"), 16, "ar = [0.5, -0.2]\nlsf = [0.1, 0.2]");
  try {
    ParseMaterial(text, "l.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("vibration.cells[0].lsf: does not match"),
              std::string::npos)
        << e.what();
  }
}

TEST(Material, SyntaxErrorsNameTheLine) {
  try {
    ParseMaterial("name = \"x\"\n[contact\n", "syn.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.diagnostics().at(0).line, 2) << e.what();
  }
}

TEST(Material, GridNeedsAllCells) {
  std::string bad = kGood;
  bad.replace(bad.find("forces_N = [0.5, 1.5]"), 21, "forces_N = [0.5, 1.0, 1.5]");
  EXPECT_THROW(ParseMaterial(bad, "g.toml"), InputError);
}

TEST(Material, TomlRoundTripWithHeightFile) {
  test::TempDir dir;
  auto m = ParseMaterial(kGood, dir.File("denim.toml"));
  m.geometry->SaveRawF32(dir.File("denim.f32"));
  test::WriteFile(dir.File("out.toml"), MaterialToToml(m, "denim.f32"));
  const auto back = LoadMaterial(dir.File("out.toml"));
  EXPECT_EQ(back.name, m.name);
  EXPECT_DOUBLE_EQ(back.contact.texture.K, m.contact.texture.K);
  EXPECT_DOUBLE_EQ(back.friction.kappa_N_per_m, m.friction.kappa_N_per_m);
  EXPECT_EQ(back.geometry->data(), m.geometry->data());
  ASSERT_EQ(back.vibration.cells.size(), 4u);
  EXPECT_EQ(back.vibration.cells[2].coeffs, m.vibration.cells[2].coeffs);
  EXPECT_EQ(back.vibration.grid_forces_N, m.vibration.grid_forces_N);
}

TEST(Material, ModelledRangeAndNoSplitRoundTripAndAreRangeChecked) {
  auto m = ParseMaterial(kGood, "r.toml");
  m.vibration.max_speed_mps = 0.25;
  m.vibration.max_force_N = 2.5;
  m.vibration.min_speed_mps = 5e-5;
  m.hybrid_cutoff_hz = 0;  // no hybrid split
  const auto back = ParseMaterial(MaterialToToml(m), "back.toml");
  EXPECT_EQ(back.vibration.max_speed_mps, 0.25);
  EXPECT_EQ(back.vibration.max_force_N, 2.5);
  EXPECT_EQ(back.vibration.min_speed_mps, 5e-5);
  EXPECT_EQ(back.hybrid_cutoff_hz, 0.0);
  std::string bad = MaterialToToml(m);
  bad.replace(bad.find("max_force_N = 2.5"), 17, "max_force_N = 0.005");
  bad.replace(bad.find("cutoff_hz = 0"), 13, "cutoff_hz = -1");
  try {
    ParseMaterial(bad, "bad.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("vibration.max_force_N: must be 0 (no limit) or > 0.01"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("hybrid.cutoff_hz: expected a number in [0, 100000] Hz, "
                                         "got -1"),
              std::string::npos)
        << e.what();
  }
}

TEST(Material, MissingHeightFileIsNamed) {
  test::TempDir dir;
  test::WriteFile(dir.File("m.toml"), R"(name = "x"
[contact]
texture_K = 100.0
[friction]
kappa_N_per_m = 100.0
mu_k = 0.2
[geometry]
file = "nope.f32"
width = 4
height = 4
pitch_m = 1e-5
)");
  try {
    LoadMaterial(dir.File("m.toml"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nope.f32"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("m.toml:8: geometry.file"), std::string::npos) << e.what();
  }
}

// docs/formats.md's key tables are printed from the field tables the reader reads through.
TEST(MaterialDocs, FormatsKeyTablesAreTheReadersTables) {
  EXPECT_EQ(test::CheckGeneratedDocBlock("docs/formats.md", "material keys", MaterialKeyTables()),
            "");
}

// Every number is checked finite and within its physical range when read, naming the line.
TEST(Material, RefusesNonFiniteAndOutOfRangeNumbersAtTheirLine) {
  struct Case {
    std::string from, to, want;
  };
  for (const Case& c : std::vector<Case>{
           {"mu_b_Ns_per_m = 0.4", "mu_b_Ns_per_m = 1e100",
            "m.toml:14: friction.mu_b_Ns_per_m: expected a number in [0, 10000] N s/m, got 1e+100"},
           {"texture_K = 800.0", "texture_K = inf",
            "m.toml:5: contact.texture_K: expected a number in (0, 1e+12] N/m^n, got inf"},
           {"sample_rate_hz = 2000", "sample_rate_hz = nan",
            "vibration.sample_rate_hz: expected a number in (0, 1e+06] Hz, got nan"},
           {"speeds_mps = [0.04, 0.08]", "speeds_mps = [0.04, 1e18]",
            "vibration.speeds_mps[1]: expected a number in [0, 100], got 1e+18"},
       }) {
    std::string text = kGood;
    ASSERT_NE(text.find(c.from), std::string::npos) << c.from;
    text.replace(text.find(c.from), c.from.size(), c.to);
    try {
      (void)ParseMaterial(text, "m.toml");
      ADD_FAILURE() << c.to << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.want), std::string::npos) << e.what();
    }
  }
  // A model built in code is checked against the same ranges.
  auto m = ParseMaterial(kGood, "fit");
  m.friction.mu_b_Ns_per_m = 1e100;
  try {
    ValidateMaterial(m);
    ADD_FAILURE() << "mu_b 1e100 was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("fit: friction.mu_b_Ns_per_m: expected a number in [0, "
                                         "10000] N s/m, got 1e+100"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace hapticlab::renderer::material_test
