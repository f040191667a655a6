// libFuzzer entry for one reader (built with clang only: -DHL_FUZZ_TARGET=<function>).
// Run: build/tests/fuzz/fuzz_<reader> tests/fuzz/corpus/<reader> -max_total_time=60

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string dir = [] {
    const auto d = std::filesystem::temp_directory_path() / "hapticlab-fuzz";
    std::filesystem::create_directories(d);
    return d.string();
  }();
  return hapticlab::fuzz::HL_FUZZ_TARGET(
      std::string_view(reinterpret_cast<const char*>(data), size), dir);
}
