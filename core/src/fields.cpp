// The non-template part of the declared field tables (core/fields.hpp): value reads with
// their messages, range texts and the Markdown rows of docs/formats.md.

#include "hapticlab/core/fields.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace hapticlab::fields {

// (core does not link fmt: numbers are printed with printf's %g.)
std::string FormatNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

bool Range::Contains(double v) const {
  if (!std::isfinite(v)) return false;
  const bool lo_ok = lo_open ? v > lo : v >= lo;
  const bool hi_ok = hi_open ? v < hi : v <= hi;
  return lo_ok && hi_ok;
}

std::string Range::ToString() const {
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (has_lo && has_hi)
    return (lo_open ? "(" : "[") + FormatNumber(lo) + ", " + FormatNumber(hi) +
           (hi_open ? ")" : "]");
  if (has_lo) return (lo_open ? "> " : ">= ") + FormatNumber(lo);
  if (has_hi) return (hi_open ? "< " : "<= ") + FormatNumber(hi);
  return "";
}

std::vector<std::string_view> SplitChoices(std::string_view choices) {
  std::vector<std::string_view> out;
  while (!choices.empty()) {
    const auto bar = choices.find('|');
    out.push_back(choices.substr(0, bar));
    if (bar == std::string_view::npos) break;
    choices.remove_prefix(bar + 1);
  }
  return out;
}

std::string JoinChoices(std::string_view choices) {
  const auto names = SplitChoices(choices);
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i)
    out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + std::string(names[i]);
  return out;
}

namespace {

// "an integer 1..100", "a non-negative integer", "an integer >= 1", "an integer".
std::string IntegerText(const Range& r) {
  if (r.lo == 0 && !r.lo_open && r.hi == std::numeric_limits<double>::infinity())
    return "a non-negative integer";
  if (std::isfinite(r.lo) && std::isfinite(r.hi) && !r.lo_open && !r.hi_open)
    return "an integer " + FormatNumber(r.lo) + ".." + FormatNumber(r.hi);
  const std::string range = r.ToString();
  return range.empty() ? "an integer" : "an integer " + range;
}

// "a number in (0, 600]", "a number >= 0", "a finite number".
std::string NumberText(const Range& r, const char* noun) {
  const std::string range = r.ToString();
  if (range.empty()) return std::string("a finite ") + noun;
  const bool interval = std::isfinite(r.lo) && std::isfinite(r.hi);
  return std::string("a ") + noun + (interval ? " in " : " ") + range;
}

}  // namespace

std::string Expected(Type type, const Range& range, std::string_view choices) {
  switch (type) {
    case Type::kString:
      return "a string";
    case Type::kBool:
      return "true or false";
    case Type::kInteger:
      return IntegerText(range);
    case Type::kNumber:
      return NumberText(range, "number");
    case Type::kStrings:
      return "an array of strings";
    case Type::kNumbers: {
      const std::string each = range.ToString();
      return each.empty()
                 ? "an array of finite numbers"
                 : "an array of numbers, each " +
                       std::string(std::isfinite(range.lo) && std::isfinite(range.hi) ? "in "
                                                                                      : "") +
                       each;
    }
    case Type::kChoice:
      return JoinChoices(choices);
    case Type::kCustom:
      break;
  }
  return "";
}

std::string ExpectedWithUnit(Type type, const Range& range, std::string_view unit,
                             std::string_view choices) {
  std::string e = Expected(type, range, choices);
  const bool numeric = type == Type::kNumber || type == Type::kNumbers || type == Type::kInteger;
  if (numeric && !unit.empty() && !range.ToString().empty()) e += " " + std::string(unit);
  return e;
}

std::string FieldReader::Full(std::string_view key) const {
  return prefix_.empty() ? std::string(key) : prefix_ + "." + std::string(key);
}

void FieldReader::Error(std::string_view key, const std::string& message) {
  const toml::node* n = t_.get(key);
  d_->Add(file_, Line(n ? n : &t_), Full(key), message);
}

void FieldReader::ErrorAt(const toml::node* n, std::string_view key, const std::string& message) {
  d_->Add(file_, Line(n ? n : &t_), Full(key), message);
}

void FieldReader::ReportUnknown(const std::vector<std::string_view>& keys) {
  for (const auto& [k, v] : t_) {
    const std::string_view key = k.str();  // (clang 14 cannot capture a structured binding)
    if (std::find(keys.begin(), keys.end(), key) == keys.end())
      d_->Add(file_, Line(&v), Full(key), "unknown key (a typo?)");
  }
}

void FieldReader::Missing(std::string_view key, const std::string& expected) {
  d_->Add(file_, Line(&t_), Full(key), "missing; expected " + expected);
}

std::optional<std::string> FieldReader::GetString(std::string_view key,
                                                  const std::string& expected) {
  if (auto v = t_.get(key)->value<std::string>()) return v;
  Error(key, "expected " + expected);
  return std::nullopt;
}

std::optional<bool> FieldReader::GetBool(std::string_view key) {
  if (const toml::node* n = t_.get(key); n->is_boolean()) return n->value<bool>();
  Error(key, "expected true or false");
  return std::nullopt;
}

std::optional<std::int64_t> FieldReader::GetInteger(std::string_view key, const Range& r,
                                                    const std::string& expected) {
  const toml::node* n = t_.get(key);
  if (!n->is_integer()) {
    Error(key, "expected " + expected);
    return std::nullopt;
  }
  // Range-checked before any narrowing cast (4294967296 must not wrap to 0).
  const std::int64_t v = *n->value<std::int64_t>();
  if (!r.Contains(static_cast<double>(v))) {
    Error(key, "expected " + expected + ", got " + std::to_string(v));
    return std::nullopt;
  }
  return v;
}

std::optional<double> FieldReader::GetNumber(std::string_view key, const Range& r,
                                             const std::string& expected) {
  const toml::node* n = t_.get(key);
  if (!n->is_number()) {
    Error(key, "expected " + expected);
    return std::nullopt;
  }
  const double v = *n->value<double>();
  if (!r.Contains(v)) {
    Error(key, "expected " + expected + ", got " + FormatNumber(v));
    return std::nullopt;
  }
  return v;
}

std::optional<std::vector<std::string>> FieldReader::GetStrings(std::string_view key) {
  const toml::array* a = t_.get(key)->as_array();
  if (!a) {
    Error(key, "expected an array of strings");
    return std::nullopt;
  }
  std::vector<std::string> out;
  bool ok = true;
  for (const auto& x : *a) {
    if (auto s = x.value<std::string>())
      out.push_back(*s);
    else
      ErrorAt(&x, key, "expected strings"), ok = false;
  }
  if (!ok) return std::nullopt;
  return out;
}

std::optional<std::vector<double>> FieldReader::GetNumbers(std::string_view key, const Range& r,
                                                           const std::string& expected) {
  const toml::array* a = t_.get(key)->as_array();
  if (!a) {
    Error(key, "expected " + expected);
    return std::nullopt;
  }
  std::vector<double> out;
  bool ok = true;
  for (std::size_t i = 0; i < a->size(); ++i) {
    const toml::node& x = (*a)[i];
    const auto v = x.is_number() ? x.value<double>() : std::nullopt;
    if (!v || !r.Contains(*v)) {
      const std::string elem = std::string(key) + "[" + std::to_string(i) + "]";
      ErrorAt(&x, elem,
              "expected " + NumberText(r, "number") + (v ? ", got " + FormatNumber(*v) : ""));
      ok = false;
      continue;
    }
    out.push_back(*v);
  }
  if (!ok) return std::nullopt;
  return out;
}

std::optional<std::size_t> FieldReader::GetChoice(std::string_view key, std::string_view choices) {
  const auto names = SplitChoices(choices);
  const auto v = t_.get(key)->value<std::string>();
  if (v) {
    const auto it = std::find(names.begin(), names.end(), *v);
    if (it != names.end()) return static_cast<std::size_t>(it - names.begin());
    Error(key, "expected " + JoinChoices(choices) + ", got '" + *v + "'");
  } else {
    Error(key, "expected " + JoinChoices(choices));
  }
  return std::nullopt;
}

namespace internal {

std::string MarkdownHeader() {
  return "| key | value | unit | default | meaning |\n|---|---|---|---|---|\n";
}

std::string MarkdownRow(std::string_view key, bool required, const std::string& expected,
                        std::string_view unit, const std::string& default_text,
                        std::string_view doc) {
  auto cell = [](std::string_view s) {
    std::string out;
    for (char c : s) out += c == '|' ? std::string("\\|") : std::string(1, c);
    return out;
  };
  return "| `" + std::string(key) + "` | " + cell(expected) + " | " + cell(unit) + " | " +
         (required ? std::string("required") : cell(default_text)) + " | " + cell(doc) + " |\n";
}

}  // namespace internal
}  // namespace hapticlab::fields
