#pragma once
// Helpers shared by the tests.

#include <cstdint>
#include <string>

#include "hapticlab/test/alloc_guard.hpp"

namespace hapticlab::test {

/// True in AddressSanitizer and ThreadSanitizer builds (-O0 or instrumented code runs 10-50x
/// slower). Property tests that sample many random states use it to take fewer samples
/// there; the release build still runs the full count.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitizerBuild = true;
#else
inline constexpr bool kSanitizerBuild = false;
#endif

/// Absolute path of a file under tests/data.
std::string DataPath(const std::string& relative);

/// A fresh temporary directory, removed (recursively) when the object is destroyed.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  std::string File(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

/// Runs a shell command, returns its exit status; stdout+stderr go to *output when given.
int RunCommand(const std::string& command, std::string* output = nullptr);

/// Writes a text file (throws on failure).
void WriteFile(const std::string& path, const std::string& text);
std::string ReadFile(const std::string& path);

}  // namespace hapticlab::test
