#pragma once
/// @file Photometric stereo (dissertation ch. IV.2): per-pixel albedo and normal from images
/// of the sample under known lights (Lambertian model, eq. 4.3), then a height map by
/// integrating the normals (Frankot-Chellappa with FFTW). OpenCV reads the images.

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace hapticlab::modeling {

/// A light of the capture rig: the image taken under it and its unit direction (towards the
/// light, z up out of the sample).
struct Light {
  std::string file;
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
};

/// The dissertation's dome: 30 lights at elevations 40°, 55°, 70°, every 36° of azimuth.
std::vector<Light> DomePreset();
/// Reads a lights file: `file,elevation_deg,azimuth_deg` or `file,lx,ly,lz` per line (header
/// optional), or the word `dome` for the preset (files light_00.png ... light_29.png).
/// @throws InputError naming the file, line and field.
std::vector<Light> LoadLights(const std::string& path);

/// Images as float intensities in [0, 1], row-major, all of one size.
struct ImageStack {
  int width = 0, height = 0;
  std::vector<std::vector<float>> images;  ///< one per light
};
/// Reads 8- or 16-bit PNG/TIFF images (grey or colour, converted to grey) with OpenCV.
/// @throws InputError naming the file on unreadable images or size mismatches.
ImageStack ReadImages(const std::string& dir, const std::vector<Light>& lights);

/// How normals become heights.
enum class Integration {
  kFrankotChellappa,  ///< FFT, periodic boundary (best for textures that tile)
  kPoisson,           ///< DCT Poisson solve, Neumann boundary (no periodicity assumed)
};

struct PhotometricOptions {
  double pitch_m = 20e-6;         ///< pixel pitch on the sample [m]
  Integration integration = Integration::kFrankotChellappa;
  double shadow_fraction = 0.05;  ///< intensities below this fraction of the pixel's maximum are shadows
  double specular_fraction = 0.1; ///< the brightest fraction of a pixel's lights is dropped when >= 6 remain
  int iterations = 3;             ///< alternations between normals and per-light intensities
};

struct PhotometricResult {
  int width = 0, height = 0;
  std::vector<float> albedo;
  std::vector<Eigen::Vector3f> normals;
  std::vector<float> height_m;    ///< integrated height [m], zero mean
  std::vector<double> light_scale;///< estimated relative intensity of each light
};

/// Albedo and normals by alternating least squares: per pixel, b = albedo * n from the
/// lights that are neither shadowed nor specular; per light, its intensity scale from all
/// pixels; repeated. `reference` (white-target images, same order) divides each image to
/// remove the lights' spatial fall-off when given. `progress` gets fractions 0..1.
PhotometricResult PhotometricStereo(const ImageStack& images, const std::vector<Light>& lights,
                                    const PhotometricOptions& options, const ImageStack* reference = nullptr,
                                    const std::function<void(double)>& progress = {});

/// Frankot-Chellappa: the height whose gradient is closest (least squares, periodic
/// boundary) to (p, q) = (dh/dx, dh/dy) in height units per pixel; scaled by pitch_m.
std::vector<float> IntegrateNormals(const std::vector<Eigen::Vector3f>& normals, int width, int height, double pitch_m);
/// The same by a Poisson solve with Neumann boundary (DCT, FFTW): lap z = div (p, q).
std::vector<float> IntegrateNormalsPoisson(const std::vector<Eigen::Vector3f>& normals, int width, int height,
                                           double pitch_m);

}  // namespace hapticlab::modeling
