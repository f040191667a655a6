#pragma once
/// @file Texture height map: heights in metres on a regular grid, bilinear sampling.
///
/// Frame: x along columns, y along rows, z the nominal surface normal; the base surface is
/// z = 0 and the texture layer's top is z = h(x, y) >= 0. Sample (i, j) (row i, column j) sits
/// at x = j * pitch_m, y = i * pitch_m. Outside the sampled area the map repeats (tiles), so
/// every position has a height and a stroke never falls off the texture.

#include <string>
#include <vector>

namespace hapticlab::renderer {

/// Height and slope at a point.
struct HeightSample {
  double h_m = 0;   ///< height above the base [m]
  double dhdx = 0;  ///< slope along x (dimensionless)
  double dhdy = 0;  ///< slope along y (dimensionless)
};

class HeightMap {
 public:
  HeightMap() = default;
  /// @param heights_m row-major, width * height values [m], all finite
  /// @param pitch_m pixel pitch [m], > 0
  /// @throws PreconditionError on size mismatch, non-finite heights or pitch <= 0
  HeightMap(int width, int height, double pitch_m, std::vector<float> heights_m);

  /// A flat map (height 0 everywhere): one pixel.
  static HeightMap Flat() { return HeightMap(1, 1, 1e-3, {0.f}); }
  /// h(x) = amplitude_m * sin(2 pi x / wavelength_m) + offset_m, sampled finely along x
  /// (constant along y). Used by the stability tool and tests.
  static HeightMap Sine(double amplitude_m, double wavelength_m, double offset_m,
                        int samples_per_wavelength = 1024);

  /// Reads raw little-endian float32 heights [m], row-major, `width * height` values.
  /// @throws hapticlab::InputError naming the file when it is missing, has the wrong size or
  /// holds non-finite values.
  static HeightMap LoadRawF32(const std::string& path, int width, int height, double pitch_m);
  /// Writes the raw little-endian float32 format.
  void SaveRawF32(const std::string& path) const;

  /// Bilinear height and its exact gradient at (x_m, y_m). Allocation-free.
  HeightSample Sample(double x_m, double y_m) const noexcept;
  /// Height normalized to [0, 1] over the map's range (0 when the map is flat): the h(x) of
  /// Table 5.1's algorithm B.
  double Normalized(double h_m) const noexcept {
    return range_m_ > 0 ? (h_m - min_m_) / range_m_ : 0.0;
  }

  int width() const { return width_; }
  int height() const { return height_; }
  double pitch_m() const { return pitch_m_; }
  double min_m() const { return min_m_; }
  double max_m() const { return min_m_ + range_m_; }
  const std::vector<float>& data() const { return data_; }

 private:
  int width_ = 1, height_ = 1;
  double pitch_m_ = 1e-3;
  double min_m_ = 0, range_m_ = 0;
  std::vector<float> data_{0.f};
};

}  // namespace hapticlab::renderer
