// The Penn Haptic Texture Toolkit importer, on files generated here in the same schema (the
// toolkit's own files may not be redistributed).

#include "hapticlab/renderer/penn_import.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/vibration.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::renderer {
namespace {

struct Generated {
  std::string xml;
  std::vector<std::vector<double>> ar;  // c_1..c_p per model
};

std::string Values(const std::vector<double>& v, const char* fmt_str) {
  std::string s;
  for (double x : v) s += fmt::format(fmt::runtime(std::string("      <value>") + fmt_str + "</value>\n"), x);
  return s;
}

// Four models at the corners of a speed x force square, two triangles (1-based).
Generated MakeXml(bool arma, int p = 10) {
  Generated g;
  const double speeds[] = {0, 200, 0, 200}, forces[] = {0.2, 0.2, 1.5, 1.5};
  std::string s = "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<modelSet texture=\"1\">\n";
  s += "   <material>Test Cloth</material>\n   <SampleRate>10000</SampleRate>\n   <mu>0.42</mu>\n";
  s += "   <numMod>4</numMod>\n   <numTri>2</numTri>\n   <speedList type=\"array\">\n";
  s += Values({speeds, speeds + 4}, "{:.6f}") + "   </speedList>\n   <forceList type=\"array\">\n";
  s += Values({forces, forces + 4}, "{:.6f}") + "   </forceList>\n";
  s += "   <tri type=\"array\">\n      <value>1</value>\n      <value>2</value>\n      <value>4</value>\n   </tri>\n";
  s += "   <tri type=\"array\">\n      <value>1</value>\n      <value>3</value>\n      <value>4</value>\n   </tri>\n";
  s += fmt::format("   <numARCoeff>{}</numARCoeff>\n", p);
  if (arma) s += "   <numMACoeff>3</numMACoeff>\n";
  for (int m = 0; m < 4; ++m) {
    std::vector<double> lsf;
    for (int k = 0; k < p; ++k) lsf.push_back((k + 0.5 + 0.2 * m) * 3.0 / (p + 1));
    const auto c = LsfToAr(lsf);
    g.ar.push_back(c);
    std::vector<double> a{1.0};
    for (double x : c) a.push_back(-x);
    s += fmt::format("   <model>\n      <modNum>{}</modNum>\n      <ARcoeff>\n", m + 1);
    s += Values(a, "{:.20f}") + "      </ARcoeff>\n      <ARlsf>\n" + Values(lsf, "{:.6f}") + "      </ARlsf>\n";
    if (arma) {
      const std::vector<double> mlsf{0.5 + 0.1 * m, 1.5, 2.5};
      const auto mc = LsfToAr(mlsf);
      std::vector<double> b{1.0};
      for (double x : mc) b.push_back(-x);
      s += "      <MAcoeff>\n" + Values(b, "{:.20f}") + "      </MAcoeff>\n      <MAlsf>\n" +
           Values(mlsf, "{:.6f}") + "      </MAlsf>\n";
      s += fmt::format("      <var>0.000000</var>\n      <gain>{:.6f}</gain>\n", 10.0 + m);
    } else {
      s += fmt::format("      <var>{:.6f}</var>\n", 0.01 * (m + 1));
    }
    s += fmt::format("      <speedMod>{:.6f}</speedMod>\n      <forceMod>{:.6f}</forceMod>\n   </model>\n",
                     speeds[m], forces[m]);
  }
  s += "</modelSet>\n";
  g.xml = s;
  return g;
}

TEST(PennImport, ReadsTheArVariant) {
  test::TempDir dir;
  const auto g = MakeXml(false);
  test::WriteFile(dir.File("Models_Test.xml"), g.xml);
  const auto r = ImportPennXml(dir.File("Models_Test.xml"));
  EXPECT_FALSE(r.arma);
  EXPECT_EQ(r.model.name, "Test Cloth");
  EXPECT_DOUBLE_EQ(r.model.friction.mu_k, 0.42);
  const auto& b = r.model.vibration;
  EXPECT_DOUBLE_EQ(b.sample_rate_hz, 10000);
  ASSERT_EQ(b.cells.size(), 4u);
  EXPECT_DOUBLE_EQ(b.cells[1].speed_mps, 0.2);  // 200 mm/s
  EXPECT_DOUBLE_EQ(b.cells[3].force_N, 1.5);
  EXPECT_DOUBLE_EQ(b.cells[2].variance, 0.03);
  ASSERT_EQ(b.triangles.size(), 2u);
  EXPECT_EQ(b.triangles[0], (std::array<int, 3>{0, 1, 3}));  // 1-based in the file
  for (std::size_t m = 0; m < 4; ++m)
    for (std::size_t i = 0; i < g.ar[m].size(); ++i) EXPECT_NEAR(b.cells[m].coeffs[i], g.ar[m][i], 1e-15);
  // The file's 6-digit LSFs rebuild its coefficients to ~1e-5.
  EXPECT_LT(r.max_lsf_reconstruction_error, 1e-5);
  // The bank plays: at a model's own point the interpolated filter is that model.
  VibrationInterpolator interp(b);
  ArFilter f;
  interp.Interpolate(0.2, 1.5, true, &f);
  for (std::size_t i = 0; i < g.ar[3].size(); ++i) EXPECT_NEAR(f.c[i], g.ar[3][i], 1e-9);
}

TEST(PennImport, ReadsTheArmaVariant) {
  test::TempDir dir;
  test::WriteFile(dir.File("Models_Arma.xml"), MakeXml(true).xml);
  const auto r = ImportPennXml(dir.File("Models_Arma.xml"));
  EXPECT_TRUE(r.arma);
  const auto& c = r.model.vibration.cells[2];
  EXPECT_EQ(c.ma.size(), 3u);
  EXPECT_DOUBLE_EQ(c.gain, 12.0);
  EXPECT_DOUBLE_EQ(c.variance, 1.0);  // var = 0 in the file: unit excitation, amplitude in gain
  EXPECT_EQ(c.ma_lsf.size(), 3u);
  VibrationInterpolator interp(r.model.vibration);
  ArFilter f;
  interp.Interpolate(0.0 + 0.011, 1.5, true, &f);  // near model 3 (0 mm/s, 1.5 N)
  EXPECT_EQ(f.ma_order, 3);
}

TEST(PennImport, ErrorsNameTheElementAndLine) {
  test::TempDir dir;
  std::string xml = MakeXml(false).xml;
  xml.replace(xml.find("<value>4</value>"), 16, "<value>9</value>");  // triangle index out of range
  const auto mu = xml.find("<mu>0.42</mu>");
  xml.replace(mu, 13, "<mu>abc</mu>");
  test::WriteFile(dir.File("bad.xml"), xml);
  try {
    ImportPennXml(dir.File("bad.xml"));
    FAIL();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("bad.xml:5: mu: expected a finite number, got 'abc'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("tri: expected three 1-based model indices in 1..4"), std::string::npos) << msg;
  }
  test::WriteFile(dir.File("broken.xml"), "<modelSet><material>x</mat");
  EXPECT_THROW(ImportPennXml(dir.File("broken.xml")), InputError);
  EXPECT_THROW(ImportPennXml(dir.File("missing.xml")), InputError);
}

}  // namespace
}  // namespace hapticlab::renderer
