// The documentation names only commands and options the CLI has: every `hapticlab ...`
// command line of README.md and docs/*.md (fenced code blocks and inline code) is resolved
// against the command tree the binary builds (cli::BuildApp), and each --option it names
// must be an option of that command or of a group above it, and the choices it lists of an
// option with a fixed set must be in the set.

#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "app.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cli_docs_test {
namespace {

struct Snippet {
  int line = 0;  // where the code block line or the paragraph holding the inline code starts
  std::string text;
};

// Inline code spans of a paragraph starting at `line` (a span may wrap), each on one line
// and with a table's "\|" read as "|".
void AddInlineCode(const std::string& paragraph, int line, std::vector<Snippet>* out) {
  static const std::regex kSpan("`([^`]+)`");
  for (std::sregex_iterator it(paragraph.begin(), paragraph.end(), kSpan), end; it != end; ++it) {
    const auto at = paragraph.begin() + it->position();
    std::string code = std::regex_replace((*it)[1].str(), std::regex(R"(\\\|)"), "|");
    std::replace(code.begin(), code.end(), '\n', ' ');
    out->push_back({line + static_cast<int>(std::count(paragraph.begin(), at, '\n')), code});
  }
}

// The code of a Markdown text: each line of a fenced block (continued by a trailing
// backslash) and each inline code span.
std::vector<Snippet> CodeSnippets(const std::string& markdown) {
  std::vector<Snippet> out;
  std::istringstream in(markdown);
  std::string l, block, paragraph;
  int n = 0, block_line = 0, paragraph_line = 0;
  bool fenced = false;
  while (std::getline(in, l)) {
    ++n;
    if (l.rfind("```", 0) == 0) {
      fenced = !fenced;
      AddInlineCode(paragraph, paragraph_line, &out);
      paragraph.clear();
    } else if (fenced) {
      if (block.empty()) block_line = n;
      block += l;
      if (!l.empty() && l.back() == '\\') continue;
      out.push_back({block_line, block});
      block.clear();
    } else if (l.find_first_not_of(" \t") == std::string::npos) {
      AddInlineCode(paragraph, paragraph_line, &out);
      paragraph.clear();
    } else {
      if (paragraph.empty()) paragraph_line = n;
      paragraph += l + "\n";
    }
  }
  AddInlineCode(paragraph, paragraph_line, &out);
  return out;
}

// The subcommand of `app` a documented word names: "show|calibrate" names its first choice.
CLI::App* Subcommand(CLI::App* app, std::string word) {
  word.erase(0, word.find_first_not_of("[("));
  if (const auto bar = word.find('|'); bar != std::string::npos) word.resize(bar);
  if (word.empty() || word[0] == '-') return nullptr;
  for (CLI::App* sub : app->get_subcommands([](CLI::App*) { return true; }))
    if (!sub->get_name().empty() && sub->check_name(word)) return sub;  // name or alias
  return nullptr;
}

const CLI::Option* FindOption(const CLI::App* app, const std::string& option) {
  for (; app != nullptr; app = app->get_parent())
    if (const CLI::Option* o = app->get_option_no_throw(option)) return o;
  return nullptr;
}

// Documented choices of an option with a fixed set ("--correction GG|HF|none" against its
// type "TEXT:{GG,HF,none}"): each must be in the set, except placeholders in capitals (N,
// FILE) that the set lacks.
void CheckChoices(const CLI::App* app, const std::string& cmd, const std::string& where,
                  std::vector<std::string>* problems) {
  static const std::regex kChoices(
      R"((--[a-z][a-z0-9-]*)[ =]([A-Za-z0-9][A-Za-z0-9:.-]*(\|[A-Za-z0-9:.-]+)+))");
  for (std::sregex_iterator it(cmd.begin(), cmd.end(), kChoices), end; it != end; ++it) {
    const CLI::Option* o = FindOption(app, (*it)[1].str());
    const std::string type = o == nullptr ? "" : o->get_type_name();
    const auto open = type.find('{'), close = type.find('}');
    if (open == std::string::npos || close == std::string::npos) continue;
    const std::string set = "," + type.substr(open + 1, close - open - 1) + ",";
    std::istringstream choices((*it)[2].str());
    for (std::string c; std::getline(choices, c, '|');)
      if (set.find("," + c + ",") == std::string::npos &&
          !std::regex_match(c, std::regex("[A-Z]+")))
        problems->push_back(where + ": " + (*it)[1].str() + " has no choice '" + c + "'");
  }
}

// One command line after "hapticlab " (`stats` true for "hapticlab-stats "): its problems,
// appended as "line: ...". Returns whether it named a command.
bool CheckCommand(CLI::App& root, const std::string& line, bool stats, int at,
                  std::vector<std::string>* problems) {
  // A comment, a second command or a redirection ends the command line.
  const std::string cmd = line.substr(0, line.find_first_of("#;&>"));
  std::istringstream words(cmd);
  CLI::App* app = stats ? root.get_subcommand("stats") : &root;
  std::string word, path = stats ? "hapticlab-stats" : "hapticlab";
  bool named = false;
  while (words >> word) {
    CLI::App* sub = Subcommand(app, word);
    if (sub == nullptr) {
      if (!named && std::regex_match(word, std::regex("[a-z][a-z0-9-]*")))
        problems->push_back(std::to_string(at) + ": " + path + ": no command '" + word + "'");
      break;
    }
    app = sub;
    path += " " + sub->get_name();
    named = true;
  }
  if (!named) return false;
  static const std::regex kOption("--[a-z][a-z0-9-]*");
  for (std::sregex_iterator it(cmd.begin(), cmd.end(), kOption), end; it != end; ++it)
    if (it->str() != "--help" && FindOption(app, it->str()) == nullptr)
      problems->push_back(std::to_string(at) + ": " + path + ": no option " + it->str());
  CheckChoices(app, cmd, std::to_string(at) + ": " + path, problems);
  return true;
}

// Where a command line starts in `code`: "hapticlab " or "hapticlab-stats " as a word (also
// after a path or a shell prompt); the position after it, and whether it is the stats binary.
struct Start {
  std::size_t name = 0;  // where "hapticlab" is
  std::size_t at = 0;    // where its command line starts
  bool stats = false;
};
std::vector<Start> CommandStarts(const std::string& code) {
  std::vector<Start> out;
  const std::string name = "hapticlab";
  for (auto p = code.find(name); p != std::string::npos; p = code.find(name, p + 1)) {
    if (p > 0 && std::string(" \t/$(").find(code[p - 1]) == std::string::npos) continue;
    // After a slash only the binary's path (build/apps/hapticlab/hapticlab, .../bin/), not the
    // source folder apps/hapticlab.
    const std::string before = code.substr(0, p);
    if (p > 0 && code[p - 1] == '/' && !before.ends_with("hapticlab/") && !before.ends_with("bin/"))
      continue;
    const std::string rest = code.substr(p + name.size(), 7);
    if (rest.rfind("-stats ", 0) == 0)
      out.push_back({p, p + name.size() + 7, true});
    else if (rest.rfind(' ', 0) == 0)
      out.push_back({p, p + name.size() + 1, false});
  }
  return out;
}

// The problems of one Markdown text; *checked counts the command lines resolved.
std::vector<std::string> Problems(const std::string& markdown, int* checked) {
  CLI::App root;
  cli::BuildApp(root);
  std::vector<std::string> problems;
  for (const Snippet& s : CodeSnippets(markdown)) {
    const auto starts = CommandStarts(s.text);
    for (std::size_t i = 0; i < starts.size(); ++i) {
      // The command line runs to the next one.
      const std::size_t end = i + 1 < starts.size() ? starts[i + 1].name : s.text.size();
      const std::string line = s.text.substr(starts[i].at, end - starts[i].at);
      if (CheckCommand(root, line, starts[i].stats, s.line, &problems)) ++*checked;
    }
  }
  return problems;
}

TEST(CliDocs, TheCheckFindsAMissingCommandAndAMissingOption) {
  int checked = 0;
  const auto problems = Problems(
      "Run `hapticlab study run P --db F --no-such-flag`, then\n"
      "```sh\nhapticlab workbench --x \\\n  --y\nhapticlab model check M --json  # fine\n```\n"
      "| `hapticlab rig show\\|calibrate\\|check ...` | fine |\n"
      "\nA span may wrap: `hapticlab study\nstatus --jsn`.\n"
      "`hapticlab analyze --db F --correction GG\\|hf\\|none --plan N\\|M`\n",
      &checked);
  ASSERT_EQ(problems.size(), 4u) << ::testing::PrintToString(problems);
  EXPECT_EQ(problems[0], "1: hapticlab study run: no option --no-such-flag");
  EXPECT_EQ(problems[1], "3: hapticlab: no command 'workbench'");
  EXPECT_EQ(problems[2], "9: hapticlab study status: no option --jsn");
  EXPECT_EQ(problems[3], "11: hapticlab analyze: --correction has no choice 'hf'");
  EXPECT_EQ(checked, 5);
}

TEST(CliDocs, EveryDocumentedCommandLineNamesCommandsAndOptionsThatExist) {
  const std::filesystem::path root(HL_SOURCE_DIR);
  std::vector<std::filesystem::path> docs{root / "README.md"};
  for (const auto& e : std::filesystem::directory_iterator(root / "docs"))
    if (e.path().extension() == ".md") docs.push_back(e.path());
  int checked = 0;
  for (const auto& doc : docs)
    for (const auto& p : Problems(test::ReadFile(doc.string()), &checked))
      ADD_FAILURE() << std::filesystem::relative(doc, root).string() << ":" << p;
  // The parse found the command lines (README's table alone has more than 40).
  EXPECT_GT(checked, 150);
}

}  // namespace
}  // namespace hapticlab::cli_docs_test
