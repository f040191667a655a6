// The Penn Haptic Texture Toolkit importer, on files generated here in the same schema (the
// toolkit's own files may not be redistributed).

#include "hapticlab/renderer/penn_import.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/hybrid.hpp"
#include "hapticlab/renderer/vibration.hpp"
#include "hapticlab/test/test_util.hpp"
#include "penn_xml.hpp"
#include "spectrum_util.hpp"

namespace hapticlab::renderer::penn_import_test {
namespace {

struct Generated {
  std::string xml;
  std::vector<std::vector<double>> ar;  // c_1..c_p per model
};

std::string Values(const std::vector<double>& v, const char* fmt_str) {
  std::string s;
  for (double x : v)
    s += fmt::format(fmt::runtime(std::string("      <value>") + fmt_str + "</value>\n"), x);
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
  s += "   <tri type=\"array\">\n      <value>1</value>\n      <value>2</value>\n      "
       "<value>4</value>\n   </tri>\n";
  s += "   <tri type=\"array\">\n      <value>1</value>\n      <value>3</value>\n      "
       "<value>4</value>\n   </tri>\n";
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
    s += Values(a, "{:.20f}") + "      </ARcoeff>\n      <ARlsf>\n" + Values(lsf, "{:.6f}") +
         "      </ARlsf>\n";
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
    s += fmt::format(
        "      <speedMod>{:.6f}</speedMod>\n      <forceMod>{:.6f}</forceMod>\n   </model>\n",
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
    for (std::size_t i = 0; i < g.ar[m].size(); ++i)
      EXPECT_NEAR(b.cells[m].coeffs[i], g.ar[m][i], 1e-15);
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
  // var = 0 in the file: the toolkit drives the model with N(0, 0) noise, so it is silent.
  EXPECT_DOUBLE_EQ(c.variance, 0.0);
  EXPECT_EQ(c.ma_lsf.size(), 3u);
  VibrationInterpolator interp(r.model.vibration);
  ArFilter f;
  interp.Interpolate(0.0 + 0.011, 1.5, true, &f);  // near model 3 (0 mm/s, 1.5 N)
  EXPECT_EQ(f.ma_order, 3);
  EXPECT_TRUE(f.active);
  EXPECT_EQ(f.sigma, 0.0);
  ArSynth synth(3);
  double energy = 0;
  for (int k = 0; k < 1000; ++k) energy += std::abs(synth.Step(f));
  EXPECT_EQ(energy, 0.0);
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
    EXPECT_NE(msg.find("bad.xml:5: mu: expected a finite number, got 'abc'"), std::string::npos)
        << msg;
    EXPECT_NE(msg.find("tri: expected three 1-based model indices in 1..4"), std::string::npos)
        << msg;
  }
  test::WriteFile(dir.File("broken.xml"), "<modelSet><material>x</mat");
  EXPECT_THROW(ImportPennXml(dir.File("broken.xml")), InputError);
  EXPECT_THROW(ImportPennXml(dir.File("missing.xml")), InputError);
}

// ---------------------------------------------------------------------------------------------
// Generated Penn-schema sets rendered end to end (import, the hybrid renderer's ticks with the
// trajectory's force, the 10 kHz vibration loop) against the toolkit's semantics and the
// analytic AR/ARMA spectrum of the model it would play.

// Renders `seconds` of a constant stroke at (speed, force) and returns the vibration samples
// after the first 0.2 s.
std::vector<double> RenderStroke(const MaterialModel& m, double speed_mmps, double force_N,
                                 double seconds, int* upsample_factor = nullptr) {
  RenderOptions o;
  o.algorithm = ForceAlgorithm::kWall;
  o.force_rate_hz = 1000;
  o.vibration_rate_hz = 10000;
  o.seed = 7;
  HybridRenderer r(m, o);
  if (upsample_factor) *upsample_factor = r.upsample_factor();
  std::vector<double> y;
  const int n = static_cast<int>(seconds * 1000);
  for (int k = 0; k < n; ++k) {
    DeviceSample s;  // on the flat surface, 0.1 mm in, sliding along x, pressing with force_N
    s.t_s = k * 1e-3;
    s.state.p_m = {speed_mmps * 1e-3 * s.t_s, 0, -1e-4};
    s.state.v_mps = {speed_mmps * 1e-3, 0, 0};
    s.has_normal_force = true;
    s.normal_force_N = force_N;
    r.ForceTick(s, s.t_s);
    for (int j = 0; j < 10; ++j) {
      const double a = r.VibrationTick();
      if (k >= 200) y.push_back(a);
    }
  }
  return y;
}

double Rms(const std::vector<double>& x) {
  double s = 0;
  for (double v : x) s += v * v;
  return std::sqrt(s / static_cast<double>(x.size()));
}

// Level within `level_tol` (relative RMS) and every band's mean PSD within `band_db` of the
// analytic PSD of the model the toolkit would play there.
void ExpectLikeToolkit(const std::vector<double>& y, const test::PennReference& ref,
                       const std::vector<std::pair<double, double>>& bands, double level_tol,
                       double band_db, const std::string& where) {
  const double expected_rms = std::sqrt(ref.Power());
  ASSERT_GT(expected_rms, 0) << where;
  EXPECT_NEAR(Rms(y) / expected_rms, 1.0, level_tol)
      << where << ": RMS " << Rms(y) << " expected " << expected_rms;
  const int n = 2048;
  const double fs = 10000;
  const auto psd = test::WelchPsdFft(y, fs, n);
  for (const auto& [lo, hi] : bands) {
    double sum = 0;
    int bins = 0;
    for (std::size_t k = 0; k < psd.size(); ++k) {
      const double f = static_cast<double>(k) * fs / n;
      if (f >= lo && f < hi) {
        sum += psd[k];
        ++bins;
      }
    }
    const double db = 10 * std::log10(sum / bins / ref.MeanPsd(lo, hi));
    EXPECT_LT(std::abs(db), band_db)
        << where << ": band " << lo << "-" << hi << " Hz off by " << db << " dB";
  }
}

struct StrokePoint {
  const char* where;
  double speed_mmps, force_N;
};

// The points of the issue: a vertex, inside a triangle, on the hull's edge, beyond the
// modelled range (saturated just inside) and at 1 mm/s (mixing the silent speed-0 models).
const StrokePoint kPoints[] = {{"vertex (170 mm/s, 0.9 N)", 170, 0.9},
                               {"inside a triangle (140 mm/s, 1.5 N)", 140, 1.5},
                               {"hull edge (200 mm/s, 2.5 N)", 200, 2.5},
                               {"beyond the range (400 mm/s, 4 N)", 400, 4.0},
                               {"1 mm/s (1 mm/s, 1.5 N)", 1, 1.5}};

TEST(PennToolkitSemantics, TenKilohertzArSetPlaysTheAnalyticSpectrumEverywhere) {
  test::TempDir dir;
  const auto spec = test::MakePennSet(false);
  test::WriteFile(dir.File("Models_AR.xml"), test::PennXml(spec));
  const auto imp = ImportPennXml(dir.File("Models_AR.xml"));
  EXPECT_TRUE(imp.has_range);
  EXPECT_DOUBLE_EQ(imp.model.vibration.max_speed_mps, 0.25);
  EXPECT_DOUBLE_EQ(imp.model.vibration.max_force_N, 2.5);
  EXPECT_EQ(imp.model.hybrid_cutoff_hz, 0.0);  // flat geometry: no split of the published vibration
  int factor = -1;
  for (const auto& p : kPoints) {
    const auto y = RenderStroke(imp.model, p.speed_mmps, p.force_N, 2.5, &factor);
    EXPECT_EQ(factor, 1);  // 10 kHz models at the 10 kHz loop
    // Level: about 500 independent samples of a 190 Hz-wide resonance: RMS sd ~3 %.
    ExpectLikeToolkit(
        y, test::PennExpected(spec, p.speed_mmps, p.force_N),
        {{50, 100}, {100, 200}, {200, 400}, {400, 800}, {800, 1600}, {1600, 3200}, {3200, 4800}},
        0.10, 1.5, p.where);
  }
}

TEST(PennToolkitSemantics, OneKilohertzArmaSetPlaysTheAnalyticSpectrumUpsampled) {
  test::TempDir dir;
  const auto spec = test::MakePennSet(true);
  test::WriteFile(dir.File("Models_ARMA.xml"), test::PennXml(spec));
  const auto imp = ImportPennXml(dir.File("Models_ARMA.xml"));
  EXPECT_TRUE(imp.arma);
  int factor = -1;
  for (const auto& p : kPoints) {
    const auto y = RenderStroke(imp.model, p.speed_mmps, p.force_N, 4.0, &factor);
    EXPECT_EQ(factor, 10);  // 1 kHz models, band-limited to the 10 kHz loop
    // Bands up to 0.45 of the model rate (the upsampler's pass band, upsampler_test.cpp).
    ExpectLikeToolkit(y, test::PennExpected(spec, p.speed_mmps, p.force_N),
                      {{20, 50}, {50, 100}, {100, 200}, {200, 300}, {300, 450}}, 0.12, 1.5,
                      p.where);
  }
}

// Light loads (issue #33): the toolkit interpolates a force below 0.05 N at 1e-4 N, next to its
// silent force-0 models; at 0.01 and 0.04 N the renderer must play that model, not the one at
// the actual force (10-25x louder on the toolkit's own files).
TEST(PennToolkitSemantics, LightLoadsPlayTheModelTheToolkitInterpolatesAtEssentiallyZero) {
  test::TempDir dir;
  const auto spec = test::MakePennSet(false);
  test::WriteFile(dir.File("Models_AR.xml"), test::PennXml(spec));
  const auto imp = ImportPennXml(dir.File("Models_AR.xml"));
  EXPECT_DOUBLE_EQ(imp.model.vibration.light_force_N, 0.05);
  for (const double force_N : {0.01, 0.04}) {
    const std::string where = fmt::format("140 mm/s, {} N", force_N);
    const auto y = RenderStroke(imp.model, 140, force_N, 2.5);
    ExpectLikeToolkit(y, test::PennExpected(spec, 140, force_N),
                      {{100, 200}, {200, 400}, {400, 800}, {800, 1600}}, 0.10, 1.5, where);
    // The actual force's model would be far louder: the rule is what makes the difference.
    const double at_actual = std::sqrt(test::PennExpected(spec, 140, force_N, false).Power());
    EXPECT_LT(Rms(y), 0.3 * at_actual) << where;
  }
  // The rule survives the material file, and 0.05 N itself is above it.
  const auto back = ParseMaterial(MaterialToToml(imp.model), "back.toml");
  EXPECT_DOUBLE_EQ(back.vibration.light_force_N, 0.05);
  VibrationInterpolator interp(back.vibration);
  ArFilter light, zero, at;
  interp.Interpolate(0.14, 0.04, true, &light);
  interp.Interpolate(0.14, kLightForceAs_N, true, &zero);
  interp.Interpolate(0.14, 0.05, true, &at);
  EXPECT_EQ(light.sigma, zero.sigma);
  EXPECT_GT(at.sigma, 10 * light.sigma);
}

TEST(PennToolkitSemantics, BoundaryModelsAreSilentAndTheRangeSaturatesJustInside) {
  test::TempDir dir;
  const auto spec = test::MakePennSet(true);
  test::WriteFile(dir.File("Models_ARMA.xml"), test::PennXml(spec));
  const auto imp = ImportPennXml(dir.File("Models_ARMA.xml"));
  VibrationInterpolator interp(imp.model.vibration);
  ArFilter f;
  // On the speed-0 boundary every weighted model has var = 0: silent, in contact. A force of 0
  // is interpolated at 1e-4 N (the light-load rule), a hair inside the silent force-0 models.
  interp.Interpolate(0.0, 1.8, true, &f);
  EXPECT_EQ(f.sigma, 0.0);
  for (const double v : {0.12, 0.2}) {
    ArFilter zero, light;
    interp.Interpolate(v, 0.0, true, &zero);
    interp.Interpolate(v, kLightForceAs_N, true, &light);
    EXPECT_EQ(zero.sigma, light.sigma) << v << " m/s";
    interp.Interpolate(v, 0.9, true, &f);
    EXPECT_LT(zero.sigma, 0.02 * f.sigma) << v << " m/s";
  }
  // Beyond the range: the filter is the one just inside (maxSpeed - 0.01 mm/s, maxForce - 0.01 N).
  ArFilter beyond, inside;
  interp.Interpolate(0.4, 4.0, true, &beyond);
  interp.Interpolate(0.25 - 1e-5, 2.5 - 0.01, true, &inside);
  EXPECT_EQ(beyond.sigma, inside.sigma);
  for (int i = 0; i < beyond.order; ++i)
    EXPECT_EQ(beyond.c[static_cast<std::size_t>(i)], inside.c[static_cast<std::size_t>(i)]);
  // The toolkit renders down to 0.05 mm/s.
  interp.Interpolate(0.06e-3, 1.5, true, &f);
  EXPECT_TRUE(f.active);
  EXPECT_GT(f.sigma, 0.0);
  interp.Interpolate(0.04e-3, 1.5, true, &f);
  EXPECT_FALSE(f.active);
}

TEST(PennImport, IntegerFieldsAreRangeCheckedBeforeConversion) {
  test::TempDir dir;
  std::string xml = test::PennXml(test::MakePennSet(false));
  xml.replace(xml.find("<numMod>11</numMod>"), 19, "<numMod>1e30</numMod>");
  const auto t = xml.find("<value>11</value>");  // a triangle vertex
  xml.replace(t, 17, "<value>4e12</value>");
  test::WriteFile(dir.File("big.xml"), xml);
  try {
    ImportPennXml(dir.File("big.xml"));
    FAIL();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("numMod: expected an integer in 1..100000, got '1e30'"), std::string::npos)
        << msg;
    EXPECT_NE(msg.find("tri: expected three 1-based model indices"), std::string::npos) << msg;
  }
}

}  // namespace
}  // namespace hapticlab::renderer::penn_import_test
