#pragma once
// Seeds and fixtures of both fuzz tests (the readers in fuzz_test.cpp, the command line in
// cli_fuzz_test.cpp): corpus files, a small study database, photometric images, vibration
// recordings, and the generated inputs of the findings too large to keep as files
// (tests/fuzz/README.md).

#include <string>
#include <vector>

namespace hapticlab::fuzz {

/// The files of tests/fuzz/corpus/<folder>, in name order.
std::vector<std::string> CorpusFiles(const std::string& folder);
/// Path of a corpus file.
std::string CorpusPath(const std::string& relative);

/// A small study record (one study, participant, session, trial, ratings and a trajectory)
/// as the bytes of a self-contained SQLite file; `scratch` is a folder to build it in.
std::string StudyDatabaseSeed(const std::string& scratch);

/// Three 8 x 8 TGA images i0.tga, i1.tga, i2.tga (corpus/image) in `dir`.
void WriteImages(const std::string& dir);
/// A lights file for i0..i2.tga in `dir` (lights.txt).
void WriteLights(const std::string& dir);
/// Four vibration recordings (corpus/recording/ar2.csv at four speeds and forces) in `dir`.
void WriteRecordings(const std::string& dir);
/// What study validate looks up next to a protocol (profiles, observer).
void WriteStudyFiles(const std::string& dir);

/// Generated findings: a protocol with `materials` materials; a lights file of `lights`
/// lines; a measurement CSV of `rows` rows; a long-format ratings CSV of `rows` rows.
std::string ProtocolWithMaterials(int materials);
std::string LightsFile(int lights);
std::string MeasurementRows(int rows);
std::string RatingRows(int rows);

}  // namespace hapticlab::fuzz
