#include "hapticlab/test/test_util.hpp"

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "hapticlab/test/doc_block.hpp"

namespace hapticlab::test {

std::string DataPath(const std::string& relative) {
  return std::string(HL_TEST_DATA_DIR) + "/" + relative;
}

TempDir::TempDir() {
  std::string tmpl = (std::filesystem::temp_directory_path() / "hltest-XXXXXX").string();
  if (!mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
  path_ = tmpl;
}
TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

int RunCommand(const std::string& command, std::string* output) {
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return -1;
  std::array<char, 4096> buf{};
  std::string out;
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) out.append(buf.data(), n);
  const int status = pclose(p);
  if (output) *output = out;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  if (!f) throw std::runtime_error("cannot write " + path);
}

std::string ReadFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("cannot read " + path);
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

std::string CheckGeneratedDocBlock(const std::string& doc_relative, const std::string& name,
                                   const std::string& expected) {
  const std::string path = std::string(HL_SOURCE_DIR) + "/" + doc_relative;
  const std::string doc = ReadFile(path);
  const std::string begin = "<!-- generated: " + name + " -->\n";
  const std::string end = "<!-- end generated: " + name + " -->";
  const auto b = doc.find(begin);
  const auto e = b == std::string::npos ? b : doc.find(end, b);
  if (e == std::string::npos) return doc_relative + " has no block '" + name + "'";
  const std::string have = doc.substr(b + begin.size(), e - b - begin.size());
  if (have == expected + "\n") return "";
  const char* update = std::getenv("HL_UPDATE_DOCS");
  if (update && std::string(update) == "1") {
    WriteFile(path, doc.substr(0, b + begin.size()) + expected + "\n" + doc.substr(e));
    return "";
  }
  std::size_t i = 0;
  while (i < have.size() && i < expected.size() && have[i] == expected[i]) ++i;
  const auto line_start = expected.rfind('\n', i == 0 ? 0 : i - 1);
  const auto from = line_start == std::string::npos ? 0 : line_start + 1;
  return doc_relative + " block '" + name + "' differs from the code's tables at:\n  doc:  " +
         have.substr(from, have.find('\n', from) - from) +
         "\n  code: " + expected.substr(from, expected.find('\n', from) - from) +
         "\n(regenerate with HL_UPDATE_DOCS=1 and the test's --gtest_filter)";
}

}  // namespace hapticlab::test
