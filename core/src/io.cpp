#include "hapticlab/core/io.hpp"

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab {

std::string ReadTextFile(const std::string& path, const std::string& what, std::size_t max_bytes) {
  // A folder opens as a stream that reads nothing: named here, not read as an empty file.
  if (std::error_code ec; std::filesystem::is_directory(path, ec))
    throw InputError(path, 0, "", "a folder, not a file: " + what + " expected");
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path, 0, "", "cannot open " + what);
  // Read in blocks and stop past the limit: the size a file claims is not trusted (a path
  // may name /dev/zero or a pipe).
  std::string text;
  char buf[1 << 16];
  while (f.read(buf, sizeof buf) || f.gcount() > 0) {
    text.append(buf, static_cast<std::size_t>(f.gcount()));
    if (text.size() > max_bytes)
      throw InputError(
          path, 0, "",
          what + " is larger than the " + std::to_string(max_bytes) + " bytes allowed");
  }
  return text;
}

void WriteTextFile(const std::string& path, std::string_view text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw std::runtime_error(path + ": cannot write");
  f.write(text.data(), static_cast<std::streamsize>(text.size()));
  f.close();
  if (!f) throw std::runtime_error(path + ": write failed");
}

namespace {

// The lexer's view of where it is in a TOML document.
class TomlLimitLexer {
 public:
  TomlLimitLexer(std::string_view text, const std::string& file) : t_(text), file_(file) {}

  void Run() {
    if (t_.size() > kTomlMaxBytes)
      Fail("", "the document is " + std::to_string(t_.size()) + " bytes, more than the " +
                   std::to_string(kTomlMaxBytes) + " allowed");
    bool statement_start = true;  // at the start of a top-level line
    while (i_ < t_.size()) {
      const char c = t_[i_];
      if (c == '\n') {
        ++line_;
        ++i_;
        if (stack_.empty()) statement_start = true;
        continue;
      }
      if (c == ' ' || c == '\t' || c == '\r') {
        ++i_;
        continue;
      }
      if (c == '#') {
        SkipComment();
        continue;
      }
      if (statement_start && stack_.empty()) {
        statement_start = false;
        if (c == '[') {
          // [table] or [[array of tables]]: the header is a key.
          ++i_;
          if (i_ < t_.size() && t_[i_] == '[') ++i_;
          Key(']');
          continue;
        }
        Key('=');
        continue;
      }
      switch (c) {
        case '"':
        case '\'':
          String();
          break;
        case '[':
        case '{':
          stack_.push_back(c);
          if (static_cast<int>(stack_.size()) > kTomlMaxNesting)
            Fail("", "arrays and inline tables nest deeper than " +
                         std::to_string(kTomlMaxNesting) + " levels");
          ++i_;
          if (c == '{') Key('=');  // an inline table starts with a key
          break;
        case ']':
        case '}':
          if (!stack_.empty()) stack_.pop_back();
          ++i_;
          break;
        case ',':
          ++i_;
          if (!stack_.empty() && stack_.back() == '{') Key('=');
          break;
        default:
          ++i_;
      }
    }
  }

 private:
  [[noreturn]] void Fail(const std::string& key, const std::string& message) const {
    throw InputError(file_, line_, key.size() > 60 ? key.substr(0, 60) + "..." : key,
                     message + " (input limits: docs/studies.md)");
  }

  void SkipComment() {
    while (i_ < t_.size() && t_[i_] != '\n') ++i_;
  }

  // A key up to `end` ('=' or ']'): counts its dotted parts and bytes. Stops (without
  // consuming) at a newline or at `end`, which it consumes.
  void Key(char end) {
    int parts = 1;
    std::size_t bytes = 0;
    const std::size_t start = i_;
    while (i_ < t_.size()) {
      const char c = t_[i_];
      if (c == '\n' || c == '#') return;  // malformed: toml++ reports it
      if (c == end) {
        ++i_;
        return;
      }
      if (c == '}' && end == '=') return;  // empty inline table
      if (c == '"' || c == '\'') {
        const std::size_t s = i_;
        String();
        bytes += i_ - s;
      } else {
        if (c == '.') ++parts;
        ++bytes;
        ++i_;
      }
      if (parts > kTomlMaxKeyParts)
        Fail(std::string(t_.substr(start, i_ - start)),
             "a key has more than " + std::to_string(kTomlMaxKeyParts) + " dotted parts");
      if (bytes > kTomlMaxKeyBytes)
        Fail(std::string(t_.substr(start, 60)),
             "a key is longer than " + std::to_string(kTomlMaxKeyBytes) + " bytes");
    }
  }

  // A string starting at i_ (basic, literal, or their multi-line forms); counts its newlines.
  void String() {
    const char q = t_[i_];
    const bool multi = t_.substr(i_, 3) == std::string_view(q == '"' ? "\"\"\"" : "'''");
    i_ += multi ? 3 : 1;
    while (i_ < t_.size()) {
      const char c = t_[i_];
      if (c == '\n') {
        if (!multi) return;  // unterminated: toml++ reports it
        ++line_;
      }
      if (c == '\\' && q == '"') {
        if (i_ + 1 < t_.size() && t_[i_ + 1] == '\n') ++line_;
        i_ += 2;
        continue;
      }
      if (c == q) {
        if (!multi) {
          ++i_;
          return;
        }
        if (t_.substr(i_, 3) == std::string_view(q == '"' ? "\"\"\"" : "'''")) {
          i_ += 3;
          while (i_ < t_.size() && t_[i_] == q) ++i_;  // up to two quotes may end the content
          return;
        }
      }
      ++i_;
    }
  }

  std::string_view t_;
  const std::string& file_;
  std::size_t i_ = 0;
  int line_ = 1;
  std::vector<char> stack_;
};

}  // namespace

void CheckTomlLimits(std::string_view text, const std::string& file) {
  TomlLimitLexer(text, file).Run();
}

}  // namespace hapticlab
