#include "hapticlab/protocols/canonical.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "hapticlab/core/toml_util.hpp"

namespace hapticlab::protocols {
namespace {

// Hand-written rather than toml++'s json_formatter: that one keeps the file's number
// spelling (2 vs 2.0) and its float format is not specified, and the form must never change
// with a library update (it is stored as the protocol's identity).
void AppendString(std::string* out, std::string_view s) {
  *out += '"';
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      *out += '\\';
      *out += c;
    } else if (u < 0x20) {
      *out += fmt::format("\\u{:04x}", static_cast<unsigned>(u));
    } else {
      *out += c;
    }
  }
  *out += '"';
}

void AppendFloat(std::string* out, double v) {
  constexpr double kExactIntegers = 9007199254740992.0;  // 2^53
  if (std::isnan(v)) {
    *out += "\"nan\"";
  } else if (std::isinf(v)) {
    *out += v > 0 ? "\"inf\"" : "\"-inf\"";
  } else if (v == std::floor(v) && std::fabs(v) < kExactIntegers) {
    *out += fmt::format("{}", static_cast<std::int64_t>(v));
  } else {
    *out += fmt::format("{}", v);  // shortest round-trip
  }
}

template <class T>
std::string Streamed(const T& v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::vector<std::string> SortedKeys(const toml::table& t) {
  std::vector<std::string> keys;
  for (const auto& [k, v] : t) keys.emplace_back(k.str());
  std::sort(keys.begin(), keys.end());
  return keys;
}

void Append(std::string* out, const toml::node& n) {
  if (const toml::table* t = n.as_table()) {
    *out += '{';
    bool first = true;
    for (const auto& k : SortedKeys(*t)) {
      if (!first) *out += ',';
      first = false;
      AppendString(out, k);
      *out += ':';
      Append(out, *t->get(k));
    }
    *out += '}';
  } else if (const toml::array* a = n.as_array()) {
    *out += '[';
    for (std::size_t i = 0; i < a->size(); ++i) {
      if (i) *out += ',';
      Append(out, (*a)[i]);
    }
    *out += ']';
  } else if (const auto s = n.value_exact<std::string>()) {
    AppendString(out, *s);
  } else if (const auto b = n.value_exact<bool>()) {
    *out += *b ? "true" : "false";
  } else if (const auto i = n.value_exact<std::int64_t>()) {
    *out += fmt::format("{}", *i);
  } else if (const auto f = n.value_exact<double>()) {
    AppendFloat(out, *f);
  } else if (const auto d = n.value_exact<toml::date>()) {
    AppendString(out, Streamed(*d));
  } else if (const auto tm = n.value_exact<toml::time>()) {
    AppendString(out, Streamed(*tm));
  } else if (const auto dt = n.value_exact<toml::date_time>()) {
    AppendString(out, Streamed(*dt));
  }
}

std::string Canonical(const toml::node* n) {
  if (!n) return "(absent)";
  std::string out;
  Append(&out, *n);
  return out;
}

bool HoldsTable(const toml::array& a) {
  return std::any_of(a.begin(), a.end(), [](const toml::node& x) { return x.is_table(); });
}

// Tables key by key, arrays that hold tables ([[material]], [[phase]]) element by element;
// any other value (arrays of scalars included) is compared whole.
void Diff(const toml::node* a, const toml::node* b, const std::string& path,
          std::vector<ProtocolChange>* out) {
  const toml::table* ta = a ? a->as_table() : nullptr;
  const toml::table* tb = b ? b->as_table() : nullptr;
  if (ta && tb) {
    std::vector<std::string> keys = SortedKeys(*ta);
    for (const auto& k : SortedKeys(*tb))
      if (!ta->contains(k)) keys.push_back(k);
    std::sort(keys.begin(), keys.end());
    for (const auto& k : keys) Diff(ta->get(k), tb->get(k), path.empty() ? k : path + "." + k, out);
    return;
  }
  const toml::array* aa = a ? a->as_array() : nullptr;
  const toml::array* ab = b ? b->as_array() : nullptr;
  if (aa && ab && (HoldsTable(*aa) || HoldsTable(*ab))) {
    for (std::size_t i = 0; i < std::max(aa->size(), ab->size()); ++i)
      Diff(aa->get(i), ab->get(i), fmt::format("{}[{}]", path, i), out);
    return;
  }
  std::string old_value = Canonical(a), new_value = Canonical(b);
  if (old_value != new_value)
    out->push_back(
        {.key = path, .old_value = std::move(old_value), .new_value = std::move(new_value)});
}

}  // namespace

std::string ProtocolChange::Describe() const {
  return fmt::format("{}: {} -> {}", key, old_value, new_value);
}

std::string CanonicalFormOfText(const std::string& toml_text, const std::string& file) {
  const toml::table doc = ParseTomlText(toml_text, file);
  return Canonical(&doc);
}

std::string CanonicalForm(const Protocol& p) { return CanonicalFormOfText(p.text, p.file); }

std::vector<ProtocolChange> CanonicalDifferences(const std::string& old_text,
                                                 const std::string& new_text) {
  const toml::table a = ParseTomlText(old_text, "the recorded protocol");
  const toml::table b = ParseTomlText(new_text, "the protocol");
  std::vector<ProtocolChange> out;
  Diff(&a, &b, "", &out);
  return out;
}

}  // namespace hapticlab::protocols
