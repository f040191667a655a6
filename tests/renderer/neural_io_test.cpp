// The neural model's file (renderer/src/neural_io.cpp): round trips of both topologies and of
// Γ_U's per-cell AR part, older format versions, and errors naming file and field.

#include <gtest/gtest.h>

#include "../modeling/neural_fixture.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::modeling::neural_io_test {
namespace {

TEST(Neural, ModelFilesRoundTripAndPlayInTheHybridRenderer) {
  test::TempDir dir;
  const auto& m = SmallModel(renderer::NeuralTopology::kDecomposed);
  const auto path = dir.File("n.toml");
  renderer::SaveNeuralModel(m, path);
  const auto back = renderer::LoadNeuralModel(path);
  renderer::NeuralSynth a(std::make_shared<renderer::NeuralModel>(m), 4),
      b(std::make_shared<renderer::NeuralModel>(back), 4);
  for (int k = 0; k < 2000; ++k) ASSERT_EQ(a.Step(0.07, 1.1, true), b.Step(0.07, 1.1, true));

  // A material referencing it: the vibration loop synthesizes with the networks.
  test::WriteFile(dir.File("mat.toml"),
                  "name = \"n\"\n[contact]\ntexture_K = 2000\n[friction]\nkappa_N_per_m = 2000\n"
                  "mu_k = 0.3\n[neural]\nfile = \"n.toml\"\n");
  const auto mat = renderer::LoadMaterial(dir.File("mat.toml"));
  ASSERT_TRUE(mat.neural);
  renderer::HybridRenderer r(mat, {});
  renderer::DeviceSample s;
  s.state.p_m = {0, 0, -0.5e-3};
  s.state.v_mps = {0.08, 0, 0};
  double power = 0;
  for (int k = 0; k < 500; ++k) {
    s.t_s = k * 1e-3;
    s.state.p_m.x() = 0.08 * s.t_s;
    r.ForceTick(s, s.t_s);
    for (int j = 0; j < 10; ++j) power += std::pow(r.VibrationTick(), 2);
  }
  EXPECT_GT(power, 0);
  renderer::RenderOptions raw;
  raw.hybrid_filter = false;  // the high-pass's own decay aside
  renderer::HybridRenderer r2(mat, raw);
  for (int k = 0; k < 100; ++k) {
    s.t_s = k * 1e-3;
    r2.ForceTick(s, s.t_s);
    for (int j = 0; j < 10; ++j) r2.VibrationTick();
  }
  s.state.p_m.z() = 1e-3;  // lifted: silent from the next vibration tick on
  r2.ForceTick(s, s.t_s);
  EXPECT_EQ(r2.VibrationTick(), 0.0);

  // Bad files name the file and key.
  std::string text = test::ReadFile(path);
  text.replace(text.find("decimation = 8"), 14, "decimation = 30");
  test::WriteFile(dir.File("bad.toml"), text);
  try {
    renderer::LoadNeuralModel(dir.File("bad.toml"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.toml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Nyquist"), std::string::npos) << e.what();
  }
  // The linear part is saved (one array per network) and its size is checked on load.
  std::string lin = test::ReadFile(path);
  const auto at = lin.find("linear = [\n  [");
  ASSERT_NE(at, std::string::npos) << "the trained model has a linear part";
  lin.insert(at + 14, "0.5, ");
  test::WriteFile(dir.File("lin.toml"), lin);
  try {
    renderer::LoadNeuralModel(dir.File("lin.toml"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("linear weights, expected 0 or"), std::string::npos)
        << e.what();
  }
}

// Γ_U's per-cell AR part (format_version 2) round-trips exactly; a version 1 file (the
// condition-basis linear part in each network, no format_version) still loads and plays; a
// newer version, a per-cell part in a version 1 file and an unstable cell filter are
// InputErrors naming the file and the field.
TEST(Neural, UnifiedModelFilesRoundTripAndOlderVersionsLoad) {
  test::TempDir dir;
  const auto& m = SmallModel(renderer::NeuralTopology::kUnified, true);
  ASSERT_EQ(m.bands[0].cell_ar.size(), 4u);
  const auto path = dir.File("u.toml");
  renderer::SaveNeuralModel(m, path);
  const std::string text = test::ReadFile(path);
  ASSERT_NE(text.find("format_version = 2\n"), std::string::npos);
  ASSERT_NE(text.find("cell_ar = [\n  ["), std::string::npos);
  const auto back = renderer::LoadNeuralModel(path);
  for (std::size_t b = 0; b < m.bands.size(); ++b) {
    EXPECT_EQ(back.bands[b].cell_ar, m.bands[b].cell_ar);
    EXPECT_EQ(back.bands[b].cell_lsf.size(), 4u) << "LSFs filled on load";
  }
  auto play = [](const renderer::NeuralModel& model) {
    renderer::NeuralSynth s(std::make_shared<renderer::NeuralModel>(model), 4);
    std::vector<double> x(3000);
    for (std::size_t k = 0; k < x.size(); ++k)
      x[k] = s.Step(0.05 + 0.06 * static_cast<double>(k) / 3000.0, 1.3, true);
    return x;
  };
  EXPECT_EQ(play(back), play(m));

  // Version 1: the linear part as condition-basis weights in each network.
  renderer::NeuralModel old = m;
  for (auto& b : old.bands) {
    const auto M = static_cast<std::size_t>(b.history);
    b.nets[0].linear.assign(9 * M, 0.0);
    for (std::size_t i = 0; i < b.cell_ar[0].size(); ++i) {  // 1: cell 1's AR; v': a slope
      b.nets[0].linear[i] = b.cell_ar[0][i];
      b.nets[0].linear[M + i] = 0.01 * b.cell_ar[3][i];
    }
    b.cell_ar.clear();
    b.cell_lsf.clear();
  }
  renderer::SaveNeuralModel(old, path);
  std::string v1 = test::ReadFile(path);
  v1.erase(v1.find("format_version = 2\n"), 19);
  test::WriteFile(dir.File("v1.toml"), v1);
  const auto old_back = renderer::LoadNeuralModel(dir.File("v1.toml"));
  EXPECT_EQ(old_back.bands[0].nets[0].linear, old.bands[0].nets[0].linear);
  EXPECT_EQ(play(old_back), play(old));

  auto expect_error = [&](const std::string& name, const std::string& body,
                          const std::vector<std::string>& parts) {
    test::WriteFile(dir.File(name), body);
    try {
      renderer::LoadNeuralModel(dir.File(name));
      ADD_FAILURE() << name << " loaded";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      for (const auto& p : parts)
        EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
    }
  };
  std::string v3 = text;
  v3.replace(v3.find("format_version = 2"), 18, "format_version = 3");
  expect_error("v3.toml", v3, {"format_version", "version 3", "versions 1 to 2"});
  std::string v1_cells = text;
  v1_cells.erase(v1_cells.find("format_version = 2\n"), 19);
  expect_error("v1cells.toml", v1_cells, {"cell_ar", "format_version = 2"});
  // The calibration state (issue #33): written and read back; absent (older files) means
  // calibrated; another word is refused naming the key.
  ASSERT_NE(text.find("calibration = \"calibrated\"\n"), std::string::npos);
  EXPECT_TRUE(back.calibrated);
  renderer::NeuralModel unc = m;
  unc.calibrated = false;
  renderer::SaveNeuralModel(unc, dir.File("unc.toml"));
  EXPECT_FALSE(renderer::LoadNeuralModel(dir.File("unc.toml")).calibrated);
  std::string none = text;
  none.erase(none.find("calibration = \"calibrated\"\n"), 27);
  test::WriteFile(dir.File("none.toml"), none);
  EXPECT_TRUE(renderer::LoadNeuralModel(dir.File("none.toml")).calibrated);
  std::string bad = text;
  bad.replace(bad.find("\"calibrated\""), 12, "\"maybe\"");
  expect_error("badcal.toml", bad, {"calibration", "\"uncalibrated\""});
  std::string unstable = text;  // first coefficient of the first cell's AR: 5 (a pole outside)
  const auto at = unstable.find("cell_ar = [\n  [") + 15;
  unstable.replace(at, unstable.find(',', at) - at, "5");
  expect_error("unstable.toml", unstable, {"cell_ar[1]", "not minimum phase"});
}
}  // namespace
}  // namespace hapticlab::modeling::neural_io_test
