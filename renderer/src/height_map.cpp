#include "hapticlab/renderer/height_map.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"

namespace hapticlab::renderer {

static_assert(std::endian::native == std::endian::little,
              "height-map files are little-endian float32; add byte swapping for this target");

HeightMap::HeightMap(int width, int height, double pitch_m, std::vector<float> heights_m)
    : width_(width), height_(height), pitch_m_(pitch_m), data_(std::move(heights_m)) {
  HL_REQUIRE(width >= 1 && height >= 1, "height map needs width, height >= 1");
  HL_REQUIRE(pitch_m > 0 && std::isfinite(pitch_m), "height map pitch_m must be positive");
  HL_REQUIRE(data_.size() == static_cast<std::size_t>(width) * static_cast<std::size_t>(height),
             "height map has " + std::to_string(data_.size()) +
                 " values, expected width*height = " +
                 std::to_string(static_cast<long long>(width) * height));
  float lo = data_[0], hi = data_[0];
  for (std::size_t i = 0; i < data_.size(); ++i) {
    HL_REQUIRE(std::isfinite(data_[i]), "height map value " + std::to_string(i) + " is not finite");
    lo = std::min(lo, data_[i]);
    hi = std::max(hi, data_[i]);
  }
  min_m_ = lo;
  range_m_ = static_cast<double>(hi) - static_cast<double>(lo);
}

HeightMap HeightMap::Sine(double amplitude_m, double wavelength_m, double offset_m,
                          int samples_per_wavelength) {
  std::vector<float> h(static_cast<std::size_t>(samples_per_wavelength));
  for (int j = 0; j < samples_per_wavelength; ++j)
    h[static_cast<std::size_t>(j)] = static_cast<float>(
        offset_m + amplitude_m * std::sin(2.0 * std::numbers::pi * j / samples_per_wavelength));
  return HeightMap(samples_per_wavelength, 1, wavelength_m / samples_per_wavelength, std::move(h));
}

HeightMap HeightMap::LoadRawF32(const std::string& path, int width, int height, double pitch_m) {
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path, 0, "", "cannot read height map: " + ec.message());
  const auto expected =
      static_cast<std::uintmax_t>(width) * static_cast<std::uintmax_t>(height) * 4u;
  if (width < 1 || height < 1 || bytes != expected)
    throw InputError(path, 0, "",
                     "height map has " + std::to_string(bytes) + " bytes; width " +
                         std::to_string(width) + " x height " + std::to_string(height) +
                         " float32 needs " + std::to_string(expected));
  std::vector<float> data(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  std::ifstream f(path, std::ios::binary);
  f.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(expected));
  if (!f) throw InputError(path, 0, "", "short read");
  for (std::size_t i = 0; i < data.size(); ++i)
    if (!std::isfinite(data[i]))
      throw InputError(path, 0, "",
                       "height at row " + std::to_string(i / static_cast<std::size_t>(width)) +
                           ", column " + std::to_string(i % static_cast<std::size_t>(width)) +
                           " is not finite");
  if (!(pitch_m > 0) || !std::isfinite(pitch_m))
    throw InputError(path, 0, "pitch_m", "a positive, finite sample pitch [m]");
  return HeightMap(width, height, pitch_m, std::move(data));
}

void HeightMap::SaveRawF32(const std::string& path) const {
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(data_.data()),
          static_cast<std::streamsize>(data_.size() * sizeof(float)));
  if (!f) throw std::runtime_error(path + ": cannot write height map");
}

HeightSample HeightMap::Sample(double x_m, double y_m) const noexcept {
  // Continuous pixel coordinates, wrapped into [0, width) x [0, height).
  double u = x_m / pitch_m_, v = y_m / pitch_m_;
  const double w = width_, hgt = height_;
  u -= std::floor(u / w) * w;
  v -= std::floor(v / hgt) * hgt;
  if (!(u >= 0 && u < w)) u = 0;  // NaN or rounding to w
  if (!(v >= 0 && v < hgt)) v = 0;
  const int j0 = static_cast<int>(u), i0 = static_cast<int>(v);
  const int j1 = j0 + 1 == width_ ? 0 : j0 + 1;
  const int i1 = i0 + 1 == height_ ? 0 : i0 + 1;
  const double fu = u - j0, fv = v - i0;
  auto at = [&](int i, int j) {
    return static_cast<double>(
        data_[static_cast<std::size_t>(i) * static_cast<std::size_t>(width_) +
              static_cast<std::size_t>(j)]);
  };
  const double h00 = at(i0, j0), h01 = at(i0, j1), h10 = at(i1, j0), h11 = at(i1, j1);
  HeightSample s;
  s.h_m = (1 - fv) * ((1 - fu) * h00 + fu * h01) + fv * ((1 - fu) * h10 + fu * h11);
  s.dhdx = ((1 - fv) * (h01 - h00) + fv * (h11 - h10)) / pitch_m_;
  s.dhdy = ((1 - fu) * (h10 - h00) + fu * (h11 - h01)) / pitch_m_;
  return s;
}

}  // namespace hapticlab::renderer
