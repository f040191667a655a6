#include "targets.hpp"

#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <new>
#include <stdexcept>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/measurement.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/export.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/renderer/penn_import.hpp"

namespace hapticlab::fuzz {
namespace {

// Runs a reader; its documented errors are fine, anything else propagates (a finding).
template <class F>
int Expect(F&& f) {
  try {
    f();
  } catch (const std::bad_alloc&) {
    throw;  // memory proportional to an unchecked number in the input
  } catch (const std::exception&) {
    // InputError, std::runtime_error: the reader refused the input.
  }
  return 0;
}

void Write(const std::string& path, std::string_view data) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(data.data(), static_cast<std::streamsize>(data.size()));
  if (!f) throw std::logic_error("fuzz: cannot write " + path);
}

}  // namespace

int Protocol(std::string_view data, const std::string& dir) {
  return Expect([&] {
    const auto p = protocols::ParseProtocol(std::string(data), dir + "/p.toml");
    // What the runner does next with a valid protocol: plan participants, check codes.
    protocols::Plan(p, 0);
    protocols::Plan(p, 3);
    protocols::CheckParticipantCode(p, "P07");
  });
}

int Material(std::string_view data, const std::string& dir) {
  return Expect([&] {
    const auto m = renderer::ParseMaterial(std::string(data), dir + "/m.toml");
    renderer::ParseMaterial(renderer::MaterialToToml(m), dir + "/m.toml");  // round trip
  });
}

int Csv(std::string_view data, const std::string&) {
  return Expect([&] {
    const auto t = ParseCsv(std::string(data), "f.csv");
    for (std::size_t r = 0; r < t.rows.size(); ++r)
      for (std::size_t c = 0; c < t.header.size(); ++c) Expect([&] { t.Number(r, c); });
  });
}

int MeasurementCsv(std::string_view data, const std::string&) {
  return Expect([&] {
    ParseMeasurementCsv(std::string(data), "m.csv");
    ParseMeasurementCsv(std::string(data), "m.csv", {.kinematics_only = true});
    ParseMeasurementCsv(std::string(data), "m.csv",
                        {.kinematics_only = true, .allow_vibration_only = true});
  });
}

int PennXml(std::string_view data, const std::string& dir) {
  const std::string path = dir + "/Models_F.xml";
  Write(path, data);
  return Expect([&] { renderer::ImportPennXml(path); });
}

int StudyDatabase(std::string_view data, const std::string& dir) {
  const std::string path = dir + "/f.db";
  for (const char* side : {"-wal", "-shm"}) std::remove((path + side).c_str());
  Write(path, data);
  return Expect([&] {
    // What analyze and export read, after their quick_check.
    const db::Database d = db::OpenForReading(path);
    for (const auto& st : d.Studies())
      for (const auto& p : d.Participants(st.id))
        for (const auto& se : d.Sessions(p.id))
          for (const auto& t : d.Trials(se.id)) {
            Expect([&] { d.Ratings(t.id); });
            Expect([&] { d.TrajectoryChunks(t.id); });
          }
    d.VerifyTrajectories();
    std::filesystem::remove_all(dir + "/export");
    db::ExportCsv(d, dir + "/export");
  });
}

}  // namespace hapticlab::fuzz
