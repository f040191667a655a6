#pragma once
/// @file A rating box (knob or slider plus a confirm button) on USB HID, read with hidapi.
/// Boxes differ, so the report layout is configuration: which report, where the position
/// lives (offset, width, byte order, raw range) and which bit is the confirm button.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hapticlab/devices/device.hpp"

namespace hapticlab::devices {

struct HidReportLayout {
  int report_id = -1;       ///< first byte of every report; -1: the device uses no report ids
  int position_offset = 0;  ///< byte offset of the position (after the report id, if any)
  int position_bytes = 2;   ///< 1 or 2
  bool little_endian = true;
  bool is_signed = false;
  double raw_min = 0, raw_max = 1023;  ///< raw values at the two ends of the travel
  int button_offset = 2;               ///< byte holding the confirm button (-1: none)
  int button_bit = 0;
};

/// Parses one input report. Reports of another id, too short, or with a NaN-free position
/// outside [raw_min, raw_max] beyond 5 % are invalid; inside, the position is clamped to 0..1.
RatingEvent ParseHidReport(const HidReportLayout& layout, const std::uint8_t* data, std::size_t n);

/// Reads a layout from TOML keys (report_id, position_offset, ...). @throws InputError.
HidReportLayout LoadHidLayout(const std::string& path);

/// hidapi back-end: opens vendor:product (and optional serial). Poll() drains the reports
/// that arrived and returns the newest. @throws std::runtime_error when the box is absent.
std::unique_ptr<RatingInput> OpenHidRating(std::uint16_t vendor_id, std::uint16_t product_id,
                                           const HidReportLayout& layout,
                                           const std::string& serial = "");

}  // namespace hapticlab::devices
