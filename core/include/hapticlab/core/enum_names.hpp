#pragma once
/// @file One generic enum <-> name table. An enum's names are written once, as a table next to
/// the enum; `NameOf` gives a value's name (for the database, a message, JSON), `FromName` the
/// value of a name, `ParseName` the same or an InputError listing the names (the CLI and file
/// edge), and `Names` every name in table order (a CLI's list of choices). Strings belong
/// only at those boundaries; code in between passes the enum.
///
///   enum class Actuator { kNone, kAudio };
///   inline constexpr EnumTable<Actuator, 2> kActuatorNames{{{Actuator::kNone, "none"},
///                                                           {Actuator::kAudio, "audio"}}};

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab {

template <typename E>
struct EnumName {
  E value;
  std::string_view name;
};

template <typename E, std::size_t N>
using EnumTable = std::array<EnumName<E>, N>;

/// The name of `value`; empty when the table lacks it (a table missing a value is a bug its
/// enum's test catches: every value has a name, every name parses back).
template <typename E, std::size_t N>
constexpr std::string_view NameOf(const EnumTable<E, N>& table, E value) {
  for (const auto& e : table)
    if (e.value == value) return e.name;
  return {};
}

/// The value named `name` (exact match), or nullopt.
template <typename E, std::size_t N>
constexpr std::optional<E> FromName(const EnumTable<E, N>& table, std::string_view name) {
  for (const auto& e : table)
    if (e.name == name) return e.value;
  return std::nullopt;
}

/// Every name, in table order.
template <typename E, std::size_t N>
std::vector<std::string> Names(const EnumTable<E, N>& table) {
  std::vector<std::string> out;
  out.reserve(N);
  for (const auto& e : table) out.emplace_back(e.name);
  return out;
}

/// The value named `name`. @throws InputError at (file, line, field): "expected one of a, b,
/// c, got 'x'".
template <typename E, std::size_t N>
E ParseName(const EnumTable<E, N>& table, std::string_view name, const std::string& file, int line,
            const std::string& field) {
  if (const auto v = FromName(table, name)) return *v;
  std::string list;
  for (const auto& e : table) list += (list.empty() ? "" : ", ") + std::string(e.name);
  throw InputError(file, line, field,
                   "expected one of " + list + ", got '" + std::string(name) + "'");
}

}  // namespace hapticlab
