#pragma once
/// @file Photometric stereo (dissertation ch. IV.2): per-pixel albedo and normal from images
/// of the sample under known lights (Lambertian model, eq. 4.3), then a height map by
/// integrating the normals (normal_integration.hpp). OpenCV reads the images.
///
/// **Image frame** (used by every direction and normal here): x along the image columns
/// (to the right), y along the image rows (downwards, row 0 at y = 0), z up out of the sample
/// towards the camera. This is the frame of the renderer's height maps (x = column, y = row).
/// Lights written in the y-up convention (x right, y up, z towards the camera) are read with
/// `y_up = true`, which negates their y component.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hapticlab/modeling/normal_integration.hpp"

namespace hapticlab::modeling {

/// A light of the capture rig: the image taken under it and its unit direction (towards the
/// light, in the image frame above).
struct Light {
  std::string file;  ///< image file name, relative to the images folder (empty: from an image list)
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  int line = 0;        ///< line of the lights file it came from (0 for presets)
  std::string source;  ///< the lights file it came from (empty for presets)
};

/// Input bounds (docs/formats.md, "Photometric stereo input"): lights in a lights file, and
/// the bytes an image stack (lights x width x height floats) may take; larger inputs are refused
/// with an InputError before they are allocated.
inline constexpr std::size_t kMaxLights = 1024;
inline constexpr std::size_t kMaxImageStackBytes = std::size_t{4} << 30;

/// The dissertation's dome: 30 lights at elevations 40°, 55°, 70°, every 36° of azimuth
/// (azimuth from +x towards +y).
std::vector<Light> DomePreset();

/// Reads a lights file, or the word `dome` for the preset (files light_00.png ... light_29.png).
/// One light per line; cells separated by commas and/or whitespace; blank lines and lines
/// starting with '#' are ignored. Accepted layouts:
///   `file elevation_deg azimuth_deg`, `file lx ly lz`, or `lx ly lz` (no file names: the
///   names come from an image list, e.g. DiLiGenT's light_directions.txt + filenames.txt).
/// Optionally a first line holding only the number of lights (checked), and/or a header line
/// naming the columns (`file,lx,ly,lz`, `file,elevation_deg,azimuth_deg` or `lx,ly,lz`).
/// Directions need not be unit length. `y_up` negates y (and mirrors the azimuth).
/// @throws InputError naming the file, line and field.
std::vector<Light> LoadLights(const std::string& path, bool y_up = false);

/// Sets the lights' file names from a list (one name per line, blank and '#' lines ignored),
/// in order; the count must match. @throws InputError naming the list file and line.
void ApplyImageList(const std::string& list_path, std::vector<Light>& lights);

/// Images as float intensities in [0, 1], row-major, all of one size.
struct ImageStack {
  int width = 0, height = 0;
  std::vector<std::vector<float>> images;  ///< one per light
};

/// One image as grey floats: every format OpenCV reads (PNG, TIFF, JPEG, BMP, PNM, PFM, EXR
/// where enabled, ...), 8/16-bit scaled to [0, 1], float kept as is, colour to grey
/// (0.299 R + 0.587 G + 0.114 B), alpha ignored, the pixel array as stored (EXIF orientation
/// ignored), plus TGA (OpenCV 4.6 has no TGA reader, so a small one is built in:
/// uncompressed and RLE, grey 8-bit and colour 16/24/32-bit).
/// @throws InputError naming the file when it cannot be read.
std::vector<float> ReadGreyImage(const std::string& path, int* width, int* height);

/// Reads one image per light (ReadGreyImage) from `dir`.
/// @throws InputError naming the file on unreadable images or size mismatches.
ImageStack ReadImages(const std::string& dir, const std::vector<Light>& lights);

/// Reads a mask image of any format ReadImages reads: a pixel is inside when any colour
/// channel is non-zero. @throws InputError when unreadable or not width x height.
std::vector<std::uint8_t> ReadMask(const std::string& path, int width, int height);

/// How lights are excluded per pixel before the Lambertian fit.
enum class Rejection {
  /// Data-driven: a light is dropped when its reading is darker than `shadow_fraction` of the
  /// pixel's fitted brightness s_j |b| (shadows), or when its studentised residual from the
  /// Lambertian fit exceeds `outlier_sigmas` robust standard deviations of all residuals
  /// (specular highlights, cast shadows, saturation); dropped lights whose residual is
  /// acceptable again are taken back. The worst outlier goes first, one at a time.
  kResidual,
  /// The earlier fixed rule, kept for comparison: lights darker than `shadow_fraction` of the
  /// pixel's brightest reading, and its brightest `specular_fraction` when >= 6 lights remain.
  kBrightest,
};

struct PhotometricOptions {
  double pitch_m = 20e-6;  ///< pixel pitch on the sample [m]
  Integration integration = Integration::kFrankotChellappa;
  Rejection rejection = Rejection::kResidual;
  double shadow_fraction = 0.05;  ///< dark-reading threshold, dimensionless (see Rejection)
  double outlier_sigmas = 3.0;    ///< residual rule: threshold in robust standard deviations
  double noise_floor = 1e-3;      ///< residual rule: least residual SD, as a fraction of s_j |b|
  int min_lights = 4;             ///< residual rule: outlier rejection never leaves fewer lights
  double specular_fraction =
      0.1;               ///< brightest rule only: the brightest fraction dropped when >= 6 remain
  int iterations = 100;  ///< most alternations between normals and per-light intensities
  /// Pixels to solve: empty = all, else width * height values, non-zero = inside. Outside
  /// pixels are neither solved nor integrated; an irregular mask needs Integration::kPoisson.
  std::vector<std::uint8_t> mask;
};

struct PhotometricResult {
  int width = 0, height = 0;
  std::vector<float> albedo;             ///< |b| (0 outside the mask and where unsolved)
  std::vector<Eigen::Vector3f> normals;  ///< unit normals, image frame; zero outside the mask
  std::vector<float> height_m;  ///< integrated height [m], zero mean inside; outside the mask the
                                ///< lowest inside height
  std::vector<std::uint8_t> mask;   ///< the pixels solved (1) or not (0)
  std::vector<double> light_scale;  ///< estimated relative intensity of each light (mean 1)
  std::vector<double> light_use;    ///< fraction of the mask's pixels that used each light
  int alternations = 0;  ///< alternations run (they stop when no light scale changes by 1e-6)
  std::size_t unsolved_pixels = 0;  ///< inside pixels with fewer than 3 usable lights (normal +z)
  double residual_sd = 0;           ///< robust SD of the kept residuals / (s_j |b|), dimensionless
  double dropped_bright = 0;  ///< fraction of inside (pixel, light) readings dropped as too bright
  double dropped_dark = 0;    ///< ... as too dark (shadows)
  /// Integrability check of the image frame: the normals' curl as given, divided by their curl
  /// with one in-plane axis mirrored (x or y; the two are indistinguishable). Well above 1
  /// means the lights' frame is probably mirrored (e.g. y-up lights read as y-down).
  double mirrored_curl_ratio = 1;
  bool axis_flip_suspected = false;  ///< mirrored_curl_ratio > kAxisFlipRatio
};

/// mirrored_curl_ratio above which a mirrored axis is reported.
inline constexpr double kAxisFlipRatio = 2.0;

/// Albedo and normals by alternating least squares: per pixel, b = albedo * n from the
/// lights that the rejection rule keeps; per light, its intensity scale from all pixels;
/// repeated. `reference` (white-target images, same order) divides each image to remove the
/// lights' spatial fall-off when given. `progress` gets fractions 0..1.
/// Preconditions (HL_REQUIRE, PreconditionError) on inconsistent inputs (image count, mask size, an
/// irregular mask with Frankot-Chellappa).
PhotometricResult PhotometricStereo(const ImageStack& images, const std::vector<Light>& lights,
                                    const PhotometricOptions& options,
                                    const ImageStack* reference = nullptr,
                                    const std::function<void(double)>& progress = {});

}  // namespace hapticlab::modeling
