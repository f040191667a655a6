#include "seeds.hpp"

#include <algorithm>
#include <filesystem>
#include <string>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::fuzz {

namespace fs = std::filesystem;

std::string CorpusPath(const std::string& relative) {
  return (fs::path(HL_SOURCE_DIR) / "tests/fuzz/corpus" / relative).string();
}

std::vector<std::string> CorpusFiles(const std::string& folder) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(CorpusPath(folder))) files.push_back(e.path());
  std::sort(files.begin(), files.end());  // a fixed order: the same mutants every run
  std::vector<std::string> out;
  for (const auto& f : files) out.push_back(test::ReadFile(f.string()));
  return out;
}

std::string StudyDatabaseSeed(const std::string& scratch) {
  const std::string path = scratch + "/seed.db";
  {
    db::Database d(path);
    const auto se = test::AddStudySession(
                        d, {.name = "f",
                            .protocol_toml = test::ReadFile(CorpusPath("protocol/small.toml")),
                            .seed = 1})
                        .session;
    const auto t = d.AddTrial({.session_id = se, .phase = PhaseKind::kMain, .material = "Denim"});
    d.StartTrial(t);
    d.InsertTrajectoryChunk({.trial_id = t,
                             .stream = "force",
                             .rate_hz = 1000,
                             .channels = {"a", "b"},
                             .samples = {1, 2, 3, 4},
                             .attempt = 1});
    d.CompleteTrial(t, {{"overall", 50, 1}},
                    {{.trial_id = t,
                      .attempt = 1,
                      .stream = "force",
                      .rate_hz = 1000,
                      .samples_offered = 2,
                      .samples_written = 2}});
    d.Exec("PRAGMA journal_mode = DELETE");  // one self-contained file
  }
  return test::ReadFile(path);
}

void WriteImages(const std::string& dir) {
  const char* names[] = {"grey8.tga", "colour16.tga", "colour24_rle.tga"};
  for (int i = 0; i < 3; ++i)
    fs::copy_file(CorpusPath(std::string("image/") + names[i]),
                  dir + "/i" + std::to_string(i) + ".tga", fs::copy_options::overwrite_existing);
}

void WriteLights(const std::string& dir) {
  test::WriteFile(dir + "/lights.txt", test::ReadFile(CorpusPath("lights/angles.txt")));
}

void WriteRecordings(const std::string& dir) {
  const std::string base = test::ReadFile(CorpusPath("recording/ar2.csv"));
  int k = 0;
  for (const char* v : {"0.04", "0.12"})
    for (const char* f : {"0.54", "1.91"}) {
      std::string s = base;
      s.replace(s.find("0.08"), 4, v);
      s.replace(s.find("1.18"), 4, f);
      test::WriteFile(dir + "/r" + std::to_string(k++) + ".csv", s);
    }
}

void WriteStudyFiles(const std::string& dir) {
  for (const char* f : {"profiles.toml", "observer.toml", "observer-start.toml"})
    fs::copy_file(fs::path(HL_SOURCE_DIR) / "studies/shin2019" / f, fs::path(dir) / f,
                  fs::copy_options::overwrite_existing);
}

std::string ProtocolWithMaterials(int materials) {
  const std::string small = test::ReadFile(CorpusPath("protocol/small.toml"));
  std::string mats;
  for (int i = 0; i < materials; ++i) mats += "[[material]]\nid = \"m" + std::to_string(i) + "\"\n";
  return small.substr(0, small.find("[[material]]")) + mats +
         small.substr(small.find("[[method]]"));
}

std::string LightsFile(int lights) {
  std::string s;
  for (int i = 0; i < lights; ++i)
    s += "i" + std::to_string(i % 3) + ".tga 45 " + std::to_string(i % 360) + "\n";
  return s;
}

std::string MeasurementRows(int rows) {
  std::string s =
      "# hapticlab-measurement v1\nt_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N\n";
  s.reserve(s.size() + static_cast<std::size_t>(rows) * 36);
  for (int i = 0; i < rows; ++i) s += std::to_string(i) + "e-4,0,0,0,0.1,0,0,0,0,-1\n";
  return s;
}

std::string RatingRows(int rows) {
  std::string s = "subject,method,material,criterion,score\n";
  s.reserve(s.size() + static_cast<std::size_t>(rows) * 24);
  for (int i = 0; i < rows; ++i)
    s += "S" + std::to_string(i % 20) + ",m" + std::to_string(i % 3) + ",a,r," +
         std::to_string(i % 97) + "\n";
  return s;
}

}  // namespace hapticlab::fuzz
