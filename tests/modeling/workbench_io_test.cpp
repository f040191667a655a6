// Workbench model files: round trip, renderer loading, renderer materials as baseline models.

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::modeling::wb::workbench_io_test {
namespace {

TEST(WorkbenchFiles, SavedModelsLoadInTheRendererAndRoundTrip) {
  TruthParams t;
  t.duration_s = 40;
  t.effects = BaselineEffects();
  t.effects.push_back("anisotropic-friction");
  const auto sim = Simulate(t);
  const auto r = PrepareReplay(sim.m);
  Model m;
  AddEffects(&m, BaselineEffects(), r);
  AddEffects(&m, {"anisotropic-friction"}, r);
  Fit(&m, r);
  test::TempDir dir;
  const auto path = std::filesystem::path(dir.path()) / "model.toml";
  SaveModel(m, path.string(), &r);
  const auto mat = renderer::LoadMaterial(path.string());
  EXPECT_EQ(mat.effects, m.effects);
  EXPECT_NEAR(mat.friction.mu_k, m.At(key::kMuK), 1e-12);
  EXPECT_NEAR(mat.contact.texture.n, m.At(key::kN), 1e-12);
  EXPECT_FALSE(mat.vibration.empty());
  const auto back = LoadModel(path.string());
  EXPECT_EQ(back.effects, m.effects);
  const auto e1 = ComputeErrors(r, Predict(m, r), Split::kAll),
             e2 = ComputeErrors(r, Predict(back, r), Split::kAll);
  EXPECT_NEAR(e1.overall, e2.overall, 1e-12);

  // The AR bank derived for the renderer has the fitted band spectrum: compare the AR cell's
  // PSD averaged over each band with the band model at that grid node (speed, force).
  const auto& cell = mat.vibration.cells[mat.vibration.cells.size() / 2];
  Replay node = r;
  node.windows.resize(1);
  node.windows[0].speed_mps = cell.speed_mps;
  node.windows[0].force_N = cell.force_N;
  node.windows[0].dir = {0, 0, 0, 0};
  const auto p = Predict(m, node);
  const double fs = mat.vibration.sample_rate_hz;
  for (std::size_t b = 0; b < r.band_lo_hz.size(); ++b) {
    double s = 0;
    const int n = 64;
    for (int k = 0; k < n; ++k) {
      const double f = r.band_lo_hz[b] * std::pow(r.band_hi_hz[b] / r.band_lo_hz[b], (k + 0.5) / n);
      // ArPsd is one-sided per Hz; the workbench's band power is per-sample two-sided.
      s += renderer::ArPsd(cell.coeffs, cell.variance, fs, f) * fs / 2;
    }
    const double db = 10 * std::log10((s / n) / p.band_power[0][b]);
    EXPECT_LT(std::abs(db), 3.0) << "band " << b << " (" << r.band_lo_hz[b] << " Hz): " << db
                                 << " dB";
  }

  // Bad files: unknown effect, missing parameters, wrong coefficient counts, each located.
  auto text = [&] {
    std::ifstream f(path);
    return std::string(std::istreambuf_iterator<char>(f), {});
  }();
  auto bad = [&](const std::string& from, const std::string& to, const std::string& expect) {
    auto s = text;
    const auto at = s.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    s.replace(at, from.size(), to);
    const auto p2 = std::filesystem::path(dir.path()) / "bad.toml";
    std::ofstream(p2) << s;
    try {
      LoadModel(p2.string());
      FAIL() << "expected an error for " << to;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.toml:"), std::string::npos) << e.what();
    }
  };
  bad("\"coulomb\", ", "\"coulomb\", \"no-such-effect\", ", "unknown effect 'no-such-effect'");
  bad("core = [", "core = [1, ", "workbench.coef.core");
  bad("K1mm_N = ", "K1mm_X = ", "workbench.params.core.K1mm_X");
  bad("[workbench.params.coulomb]\nmu_k = ", "[workbench.params.coulomb]\nmu_k = \"high\" #",
      "workbench.params.coulomb.mu_k");
}

// Issue #33: SaveModel never leaves a file it would refuse to read (a bias-corrected mu_b of
// -0.000123 was written, then refused as bad input, exit 2): the model is read back before it
// replaces the target; a model that does not read back is the program's error
// (PreconditionError, nothing written, the old file kept), a file that cannot be written an
// environment failure (std::runtime_error), neither an InputError (exit 2).
TEST(WorkbenchFiles, AModelThatWouldNotReadBackIsNeverWritten) {
  test::TempDir dir;
  const auto in = std::filesystem::path(dir.path()) / "mat.toml";
  std::ofstream(in) << "name = \"m\"\n[contact]\ntexture_K = 2000\n"
                       "[friction]\nkappa_N_per_m = 2500\nmu_k = 0.35\nmu_b_Ns_per_m = 0.2\n";
  Model m = LoadModel(in.string());
  const auto out = std::filesystem::path(dir.path()) / "out.toml";
  SaveModel(m, out.string());
  EXPECT_NEAR(LoadModel(out.string()).At(key::kMuB_Ns_per_m), 0.2, 1e-12);
  const std::string before = test::ReadFile(out.string());
  m.Set(key::kMuB_Ns_per_m, -1.23e-4);
  try {
    SaveModel(m, out.string());
    FAIL() << "a model with mu_b < 0 was written";
  } catch (const PreconditionError& e) {
    EXPECT_NE(std::string(e.what()).find("friction.mu_b_Ns_per_m"), std::string::npos) << e.what();
  }
  EXPECT_EQ(test::ReadFile(out.string()), before) << "the old file is kept";
  EXPECT_FALSE(std::filesystem::exists(out.string() + ".writing"));
  m.Set(key::kMuB_Ns_per_m, 0.0);  // at its bound: reads back
  SaveModel(m, out.string());
  EXPECT_EQ(LoadModel(out.string()).At(key::kMuB_Ns_per_m), 0.0);
  const auto nowhere = std::filesystem::path(dir.path()) / "no" / "such" / "dir" / "x.toml";
  try {
    SaveModel(m, nowhere.string());
    FAIL() << "wrote into a missing folder";
  } catch (const InputError&) {
    FAIL() << "an unwritable path is not bad input";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot write"), std::string::npos) << e.what();
  }
}

TEST(WorkbenchFiles, RendererMaterialsAreReadAsBaselineModels) {
  test::TempDir dir;
  const auto path = std::filesystem::path(dir.path()) / "mat.toml";
  std::ofstream(path) << "name = \"m\"\n[contact]\ntexture_K = 2000\ntexture_B = 5\ntexture_n = 1\n"
                         "[friction]\nkappa_N_per_m = 2500\nmu_k = 0.35\nmu_b_Ns_per_m = 0.2\n";
  const auto m = LoadModel(path.string());
  EXPECT_TRUE(m.Has("coulomb") && m.Has("dahl") && m.Has("viscous") && m.Has("hc-damping"));
  EXPECT_FALSE(m.Has("hc-exponent"));
  EXPECT_NEAR(m.At(key::kK1mm_N), 2.0, 1e-12);  // 2000 N/m at 1 mm
  EXPECT_NEAR(m.At(key::kMuK), 0.35, 1e-12);
  std::ofstream(path) << "name = \"m\"\neffects = [\"stribeck\"]\n[contact]\ntexture_K = 2000\n"
                         "[friction]\nkappa_N_per_m = 2500\nmu_k = 0.35\n";
  try {
    LoadModel(path.string());
    FAIL();
  } catch (const InputError& e) {
    // Located in the file, and no CLI command named (library code; docs/architecture.md "Errors").
    bool found = false;
    for (const auto& d : e.diagnostics()) {
      if (d.message.find("effect 'stribeck' has no parameters") == std::string::npos) continue;
      found = true;
      EXPECT_EQ(d.file, path.string());
      EXPECT_EQ(d.field, "effects");
      EXPECT_EQ(d.message.find("hapticlab"), std::string::npos) << d.message;
    }
    EXPECT_TRUE(found) << e.what();
  }
}

}  // namespace
}  // namespace hapticlab::modeling::wb::workbench_io_test
