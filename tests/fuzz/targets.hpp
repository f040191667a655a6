#pragma once
// One fuzz entry point per reader of untrusted input. Each parses `data` the way the
// program does and returns normally for any input, valid or not: the reader's own errors
// (InputError, std::runtime_error) are expected and swallowed. A
// crash, a sanitizer report, an allocation failure (std::bad_alloc: memory proportional to an
// unchecked number) or a hang is a finding. Used by the gtest mutation harness
// (fuzz_test.cpp) and, when built with clang, by one libFuzzer binary per target.

#include <string>
#include <string_view>

namespace hapticlab::fuzz {

/// `dir` is a scratch folder the target may write files into (Penn XML, databases).
int Protocol(std::string_view data, const std::string& dir);
int Material(std::string_view data, const std::string& dir);
int Csv(std::string_view data, const std::string& dir);
int MeasurementCsv(std::string_view data, const std::string& dir);
int PennXml(std::string_view data, const std::string& dir);
int StudyDatabase(std::string_view data, const std::string& dir);

}  // namespace hapticlab::fuzz
