#include "hapticlab/devices/hid_rating.hpp"

#include <fmt/format.h>
#include <hidapi/hidapi.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/toml_util.hpp"

namespace hapticlab::devices {

RatingEvent ParseHidReport(const HidReportLayout& L, const std::uint8_t* d, std::size_t n) {
  RatingEvent e;
  std::size_t base = 0;
  if (L.report_id >= 0) {
    if (n < 1 || d[0] != L.report_id) return e;
    base = 1;
  }
  const std::size_t pos = base + static_cast<std::size_t>(L.position_offset);
  if (L.position_bytes < 1 || L.position_bytes > 2 ||
      pos + static_cast<std::size_t>(L.position_bytes) > n)
    return e;
  std::uint32_t raw = d[pos];
  if (L.position_bytes == 2)
    raw = L.little_endian ? (d[pos] | (d[pos + 1] << 8)) : ((d[pos] << 8) | d[pos + 1]);
  double v = static_cast<double>(raw);
  if (L.is_signed)
    v = L.position_bytes == 2 ? static_cast<double>(static_cast<std::int16_t>(raw))
                              : static_cast<double>(static_cast<std::int8_t>(raw));
  const double span = L.raw_max - L.raw_min;
  if (span == 0) return e;
  const double x = (v - L.raw_min) / span;
  if (x < -0.05 || x > 1.05) return e;  // out of the box's range: a glitch or the wrong layout
  e.position = std::clamp(x, 0.0, 1.0);
  if (L.button_offset >= 0) {
    const std::size_t b = base + static_cast<std::size_t>(L.button_offset);
    if (b >= n) return e;
    e.confirm = (d[b] >> L.button_bit) & 1;
  }
  e.valid = true;
  return e;
}

HidReportLayout LoadHidLayout(const std::string& path) {
  const toml::table t = ParseTomlFile(path);
  Diagnostics d;
  HidReportLayout L;
  // Range-checked before the conversion (an offset outside a 64-byte report would index
  // past the buffer).
  auto num = [&](const char* k, auto* out, double lo, double hi) {
    if (const auto* n = t.get(k)) {
      const auto v = n->value<double>();
      if (v && *v >= lo && *v <= hi)
        *out = static_cast<std::remove_pointer_t<decltype(out)>>(*v);
      else
        d.Add(path, static_cast<int>(n->source().begin.line), k,
              fmt::format("expected a number in {}..{}", lo, hi));
    }
  };
  num("report_id", &L.report_id, -1, 255);
  num("position_offset", &L.position_offset, 0, 62);
  num("position_bytes", &L.position_bytes, 1, 2);
  num("raw_min", &L.raw_min, -1e9, 1e9);
  num("raw_max", &L.raw_max, -1e9, 1e9);
  num("button_offset", &L.button_offset, -1, 63);
  num("button_bit", &L.button_bit, 0, 7);
  if (auto v = t["little_endian"].value<bool>()) L.little_endian = *v;
  if (auto v = t["signed"].value<bool>()) L.is_signed = *v;
  for (const auto& [k, v] : t) {
    static const char* known[] = {"report_id", "position_offset", "position_bytes", "raw_min",
                                  "raw_max",   "button_offset",   "button_bit",     "little_endian",
                                  "signed",    "vendor_id",       "product_id",     "serial"};
    if (std::find(std::begin(known), std::end(known), k.str()) == std::end(known))
      d.Add(path, static_cast<int>(v.source().begin.line), std::string(k.str()), "unknown key");
  }
  if (L.position_bytes != 1 && L.position_bytes != 2)
    d.Add(path, 0, "position_bytes", "expected 1 or 2");
  if (L.raw_max == L.raw_min) d.Add(path, 0, "raw_max", "must differ from raw_min");
  if (L.button_bit < 0 || L.button_bit > 7) d.Add(path, 0, "button_bit", "expected 0..7");
  d.ThrowIfAny();
  return L;
}

namespace {
class HidapiRating final : public RatingInput {
 public:
  HidapiRating(std::uint16_t vid, std::uint16_t pid, const HidReportLayout& L,
               const std::string& serial)
      : L_(L) {
    if (hid_init() != 0) throw std::runtime_error("hidapi: cannot initialise");
    std::wstring ws(serial.begin(), serial.end());
    h_ = hid_open(vid, pid, serial.empty() ? nullptr : ws.c_str());
    if (!h_)
      throw std::runtime_error(fmt::format(
          "rating box {:04x}:{:04x} not found (permissions? docs/hardware.md)", vid, pid));
    hid_set_nonblocking(h_, 1);
  }
  ~HidapiRating() override {
    hid_close(h_);
    hid_exit();
  }
  RatingEvent Poll() override {
    RatingEvent last;
    std::uint8_t buf[64];
    for (int k = 0; k < 64; ++k) {  // drain, keep the newest valid report
      const int n = hid_read(h_, buf, sizeof buf);
      if (n <= 0) break;
      const auto e = ParseHidReport(L_, buf, static_cast<std::size_t>(n));
      if (e.valid) last = e;
    }
    return last;
  }

 private:
  HidReportLayout L_;
  hid_device* h_ = nullptr;
};
}  // namespace

std::unique_ptr<RatingInput> OpenHidRating(std::uint16_t vid, std::uint16_t pid,
                                           const HidReportLayout& L, const std::string& serial) {
  return std::make_unique<HidapiRating>(vid, pid, L, serial);
}

}  // namespace hapticlab::devices
