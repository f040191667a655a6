#pragma once
/// @file Declared field tables for user TOML files (Drake's Serialize idea): a struct's file
/// keys are declared once, each with its type, unit, allowed range, whether it is required and
/// a line of documentation, and bound to the struct member it fills. From that one table
/// follow the reader (`FieldReader::Read`: unknown keys, types, finiteness, ranges, every
/// problem as file:line: table.key: expected ...), the validator of structs built in code
/// (`CheckFields`) and the key tables of docs/formats.md (`FieldsMarkdown`, checked against
/// the document by the tests). Keys whose meaning needs code (a pair list, a cross-check)
/// are declared as `Type::kCustom`: listed and documented, read by hand.
///
/// Like core/toml_util.hpp this header uses toml++: a target including it links
/// tomlplusplus::tomlplusplus.
///
/// Declaring a table (a free function returning a static array keeps it in one place):
/// @code
///   std::span<const fields::Field<Breaks>> BreakFields() {
///     static const fields::Field<Breaks> kFields[] = {
///         {.key = "duration_s", .type = fields::Type::kNumber,
///          .ref = HL_FIELD_REF(Breaks, duration_s), .range = {0, 3600}, .unit = "s",
///          .doc = "length of each break"}};
///     return kFields;
///   }
///   fields::FieldReader(table, "breaks", file, &diag).Read(BreakFields(), &breaks);
/// @endcode

#include <toml++/toml.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::fields {

enum class Type {
  kString,   ///< a string
  kBool,     ///< true or false
  kInteger,  ///< a TOML integer within `range`
  kNumber,   ///< a finite number (integer or float) within `range`
  kStrings,  ///< an array of strings
  kNumbers,  ///< an array of finite numbers, each within `range`
  kChoice,   ///< one of the names in `choices` ("a|b|c"), stored through a setter
  kCustom,   ///< declared and documented here, read by the table's own code
};

/// The values a number may take: [lo, hi], either end open. Non-finite values are never in it.
struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;
  bool hi_open = false;
  bool Contains(double v) const;
  /// "(0, 600]", "[0, 1e+06]", "> 0", ">= 0", "<= 10"; "" for the whole real line.
  std::string ToString() const;
};
/// (lo, hi]
constexpr Range OpenClosed(double lo, double hi) { return {lo, hi, true, false}; }
/// [lo, hi)
constexpr Range ClosedOpen(double lo, double hi) { return {lo, hi, false, true}; }
/// > lo
constexpr Range Above(double lo) { return {lo, std::numeric_limits<double>::infinity(), true}; }

/// Where a field's value goes in the struct S: an accessor returning the member (see
/// HL_FIELD_REF), or for kChoice a setter given the index of the chosen name. monostate for
/// kCustom fields.
template <class S>
using Ref = std::variant<std::monostate, std::string& (*)(S&), bool& (*)(S&), int& (*)(S&),
                         std::uint64_t& (*)(S&), double& (*)(S&), std::vector<std::string>& (*)(S&),
                         std::vector<double>& (*)(S&), void (*)(S&, std::size_t)>;

/// One key of a table, bound to a member of S.
template <class S>
struct Field {
  std::string_view key;
  Type type = Type::kCustom;
  Ref<S> ref{};
  Range range{};            ///< kInteger, kNumber, kNumbers
  std::string_view unit{};  ///< SI symbol (or _dB, ...) of the value; "" dimensionless
  bool required = false;
  std::string_view doc{};           ///< one line for docs/formats.md
  std::string_view choices{};       ///< kChoice: the names, '|'-separated
  std::string_view default_text{};  ///< docs: the default when S{} does not show it
  std::string_view expected{};      ///< kCustom: what the value must be (messages, docs)
  /// kChoice: the index of the struct's current choice (for defaults in docs and CheckFields).
  std::size_t (*chosen)(const S&) = nullptr;
};

/// `+[](S& s) -> T& { return s.member; }` for a member path of S (`texture.K` works too).
// NOLINTNEXTLINE(bugprone-macro-parentheses): S is a type and member a member path
#define HL_FIELD_REF(S, member) (+[](S & s_) -> auto& { return s_.member; })

/// What a value must be, for docs: "a number in (0, 600]", "an integer 1..100".
std::string Expected(Type type, const Range& range, std::string_view choices);
/// The same with the unit, for messages: "a number in (0, 600] s".
std::string ExpectedWithUnit(Type type, const Range& range, std::string_view unit,
                             std::string_view choices);
/// Expected() of a field (its own text for kCustom).
template <class S>
std::string Expected(const Field<S>& f) {
  return f.type == Type::kCustom ? std::string(f.expected) : Expected(f.type, f.range, f.choices);
}
/// The choices of a kChoice field: "full|blocked" -> {"full", "blocked"}.
std::vector<std::string_view> SplitChoices(std::string_view choices);
/// "a, b or c".
std::string JoinChoices(std::string_view choices);
/// The shortest decimal text of v ("600", "1e+06", "0.5").
std::string FormatNumber(double v);

/// Reads one TOML table through its field table, recording every problem in `d` as
/// `file:line: prefix.key: message`.
class FieldReader {
 public:
  FieldReader(const toml::table& t, std::string prefix, std::string file, Diagnostics* d)
      : t_(t), prefix_(std::move(prefix)), file_(std::move(file)), d_(d) {}

  /// Refuses keys not in `fields`, then reads every field that is not kCustom into `*s`: a
  /// missing required key, a value of the wrong type, a non-finite number or one outside its
  /// range is reported and leaves the member as it was.
  template <class S>
  void Read(std::span<const Field<S>> fields, S* s);
  /// Only the unknown-key check of Read.
  template <class S>
  void CheckKnown(std::span<const Field<S>> fields);

  // For kCustom fields and cross-checks.
  static int Line(const toml::node* n) { return n ? static_cast<int>(n->source().begin.line) : 0; }
  const toml::node* Get(std::string_view key) const { return t_.get(key); }
  bool Has(std::string_view key) const { return t_.contains(key); }
  std::string Full(std::string_view key) const;
  /// Reports a problem with `key` at its line (the table's line when the key is absent).
  void Error(std::string_view key, const std::string& message);
  /// Reports a problem at node `n` (an array element) under `key`.
  void ErrorAt(const toml::node* n, std::string_view key, const std::string& message);
  const toml::table& table() const { return t_; }
  const std::string& file() const { return file_; }
  const std::string& prefix() const { return prefix_; }
  Diagnostics& diag() { return *d_; }

 private:
  // One field's value into *s, or a reported problem. Non-template part in fields.cpp.
  template <class S>
  void ReadOne(const Field<S>& f, S* s);
  bool KeyKnown(std::string_view key, const std::vector<std::string_view>& keys) const;
  void ReportUnknown(const std::vector<std::string_view>& keys);
  void Missing(std::string_view key, const std::string& expected);
  std::optional<std::string> GetString(std::string_view key, const std::string& expected);
  std::optional<bool> GetBool(std::string_view key);
  std::optional<std::int64_t> GetInteger(std::string_view key, const Range& r,
                                         const std::string& expected);
  std::optional<double> GetNumber(std::string_view key, const Range& r,
                                  const std::string& expected);
  std::optional<std::vector<std::string>> GetStrings(std::string_view key);
  std::optional<std::vector<double>> GetNumbers(std::string_view key, const Range& r,
                                                const std::string& expected);
  std::optional<std::size_t> GetChoice(std::string_view key, std::string_view choices);

  const toml::table& t_;
  std::string prefix_, file_;
  Diagnostics* d_;
};

/// Checks the number and integer members of a struct built in code (a fit, an import)
/// against the same table: finite and within range; problems as `file:0: prefix.key: ...`.
template <class S>
void CheckFields(std::span<const Field<S>> fields, const S& s, const std::string& prefix,
                 const std::string& file, Diagnostics* d);

/// The table's Markdown key table for docs/formats.md: key, type and range, unit, default
/// (from S{} unless the field says), meaning.
template <class S>
std::string FieldsMarkdown(std::span<const Field<S>> fields, const S& defaults = S{});

// ---- implementation ----

namespace internal {
std::string MarkdownRow(std::string_view key, bool required, const std::string& expected,
                        std::string_view unit, const std::string& default_text,
                        std::string_view doc);
std::string MarkdownHeader();
}  // namespace internal

template <class S>
void FieldReader::CheckKnown(std::span<const Field<S>> fields) {
  std::vector<std::string_view> keys;
  keys.reserve(fields.size());
  for (const auto& f : fields) keys.push_back(f.key);
  ReportUnknown(keys);
}

template <class S>
void FieldReader::Read(std::span<const Field<S>> fields, S* s) {
  CheckKnown(fields);
  for (const auto& f : fields)
    if (f.type != Type::kCustom) ReadOne(f, s);
}

template <class S>
void FieldReader::ReadOne(const Field<S>& f, S* s) {
  const std::string expected = ExpectedWithUnit(f.type, f.range, f.unit, f.choices);
  if (!t_.contains(f.key)) {
    if (f.required) Missing(f.key, expected);
    return;
  }
  switch (f.type) {
    case Type::kString:
      if (auto v = GetString(f.key, expected)) std::get<std::string& (*)(S&)>(f.ref)(*s) = *v;
      break;
    case Type::kBool:
      if (auto v = GetBool(f.key)) std::get<bool& (*)(S&)>(f.ref)(*s) = *v;
      break;
    case Type::kInteger:
      if (auto v = GetInteger(f.key, f.range, expected)) {
        if (auto* r = std::get_if<int& (*)(S&)>(&f.ref))
          (*r)(*s) = static_cast<int>(*v);
        else
          std::get<std::uint64_t& (*)(S&)>(f.ref)(*s) = static_cast<std::uint64_t>(*v);
      }
      break;
    case Type::kNumber:
      if (auto v = GetNumber(f.key, f.range, expected)) std::get<double& (*)(S&)>(f.ref)(*s) = *v;
      break;
    case Type::kStrings:
      if (auto v = GetStrings(f.key))
        std::get<std::vector<std::string>& (*)(S&)>(f.ref)(*s) = std::move(*v);
      break;
    case Type::kNumbers:
      if (auto v = GetNumbers(f.key, f.range, expected))
        std::get<std::vector<double>& (*)(S&)>(f.ref)(*s) = std::move(*v);
      break;
    case Type::kChoice:
      if (auto v = GetChoice(f.key, f.choices)) std::get<void (*)(S&, std::size_t)>(f.ref)(*s, *v);
      break;
    case Type::kCustom:
      break;
  }
}

template <class S>
void CheckFields(std::span<const Field<S>> fields, const S& s, const std::string& prefix,
                 const std::string& file, Diagnostics* d) {
  S& m = const_cast<S&>(s);  // the accessors only read here
  for (const auto& f : fields) {
    const std::string key = prefix.empty() ? std::string(f.key) : prefix + "." + std::string(f.key);
    const std::string expected = ExpectedWithUnit(f.type, f.range, f.unit, f.choices);
    auto check = [&](double v) {
      if (!f.range.Contains(v))
        d->Add(file, 0, key, "expected " + expected + ", got " + FormatNumber(v));
    };
    if (f.type == Type::kNumber) check(std::get<double& (*)(S&)>(f.ref)(m));
    if (f.type == Type::kNumbers)
      for (double v : std::get<std::vector<double>& (*)(S&)>(f.ref)(m)) check(v);
    if (f.type == Type::kInteger) {
      if (auto* r = std::get_if<int& (*)(S&)>(&f.ref))
        check(static_cast<double>((*r)(m)));
      else
        check(static_cast<double>(std::get<std::uint64_t& (*)(S&)>(f.ref)(m)));
    }
  }
}

template <class S>
std::string FieldsMarkdown(std::span<const Field<S>> fields, const S& defaults) {
  S m = defaults;
  std::string out = internal::MarkdownHeader();
  for (const auto& f : fields) {
    std::string def(f.default_text);
    if (def.empty() && !f.required) {
      switch (f.type) {
        case Type::kString:
          def = "\"" + std::get<std::string& (*)(S&)>(f.ref)(m) + "\"";
          break;
        case Type::kBool:
          def = std::get<bool& (*)(S&)>(f.ref)(m) ? "true" : "false";
          break;
        case Type::kInteger:
          if (auto* r = std::get_if<int& (*)(S&)>(&f.ref))
            def = std::to_string((*r)(m));
          else
            def = std::to_string(std::get<std::uint64_t& (*)(S&)>(f.ref)(m));
          break;
        case Type::kNumber:
          def = FormatNumber(std::get<double& (*)(S&)>(f.ref)(m));
          break;
        case Type::kChoice:
          if (f.chosen) def = "\"" + std::string(SplitChoices(f.choices)[f.chosen(m)]) + "\"";
          break;
        default:
          break;
      }
    }
    out += internal::MarkdownRow(f.key, f.required, Expected(f), f.unit, def, f.doc);
  }
  return out;
}

}  // namespace hapticlab::fields
