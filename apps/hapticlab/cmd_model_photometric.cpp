// hapticlab model photometric: height map, normals and albedo from photometric stereo.

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <limits>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "cli_common.hpp"
#include "cmd_model.hpp"
#include "commands.hpp"
#include "fit_summary_json.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/measurement.hpp"
#include "hapticlab/modeling/contact.hpp"
#include "hapticlab/modeling/neural.hpp"
#include "hapticlab/modeling/photometric.hpp"
#include "hapticlab/modeling/vibration.hpp"
#include "hapticlab/renderer/energy.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/renderer/penn_import.hpp"
#include "hapticlab/runner/offline.hpp"
#include "hapticlab/stats/plot.hpp"

namespace hapticlab::cli {
namespace {

// The photometric command's outputs (normals, albedo) and its options' checks.
namespace photometric_out {

std::string Extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  for (auto& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

bool IsTiff(const std::string& path) {
  return Extension(path) == ".tif" || Extension(path) == ".tiff";
}

// Refuses an output name whose extension has no writer here, before any work.
void CheckImageOutput(const std::string& path, const std::string& option) {
  if (!path.empty() && !IsTiff(path) && Extension(path) != ".png")
    throw InputError(kCommandLine, 0, option,
                     path + ": .png (8/16-bit) or .tif/.tiff (32-bit float) expected");
}

// Normals: PNG as 8-bit RGB = round(127.5 (n + 1)), TIFF as float RGB = (x, y, z); zero
// outside the mask. `y_up` writes y upwards (the frame of y-up lights).
void WriteNormals(const std::string& path, const modeling::PhotometricResult& r, bool y_up) {
  const bool tiff = IsTiff(path);
  cv::Mat m(r.height, r.width, tiff ? CV_32FC3 : CV_8UC3, cv::Scalar::all(0));
  for (int i = 0; i < r.height; ++i)
    for (int j = 0; j < r.width; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * static_cast<std::size_t>(r.width) +
                            static_cast<std::size_t>(j);
      if (!r.mask[k]) continue;
      const Eigen::Vector3f n(r.normals[k].x(), y_up ? -r.normals[k].y() : r.normals[k].y(),
                              r.normals[k].z());
      if (tiff) {
        m.at<cv::Vec3f>(i, j) =
            cv::Vec3f(n.z(), n.y(), n.x());  // OpenCV's B, G, R: the file holds x, y, z
      } else {
        auto q = [](float c) {
          return static_cast<unsigned char>(
              std::clamp(std::lround(127.5 * (static_cast<double>(c) + 1)), 0L, 255L));
        };
        m.at<cv::Vec3b>(i, j) = cv::Vec3b(q(n.z()), q(n.y()), q(n.x()));
      }
    }
  // Uncompressed: OpenCV 4.6 writes 3-channel float TIFF as lossy LogLuv (SGILOG) by default.
  const std::vector<int> params =
      tiff ? std::vector<int>{cv::IMWRITE_TIFF_COMPRESSION, 1} : std::vector<int>{};
  if (!cv::imwrite(path, m, params)) throw std::runtime_error(path + ": cannot write");
}

// Albedo: TIFF as float (|b|, relative to the mean light), PNG as 16-bit scaled so that the
// largest albedo is 65535.
void WriteAlbedo(const std::string& path, const modeling::PhotometricResult& r) {
  cv::Mat f(r.height, r.width, CV_32F, const_cast<float*>(r.albedo.data()));
  if (IsTiff(path)) {
    if (!cv::imwrite(path, f)) throw std::runtime_error(path + ": cannot write");
    return;
  }
  const float mx = *std::max_element(r.albedo.begin(), r.albedo.end());
  cv::Mat u;
  f.convertTo(u, CV_16U, mx > 0 ? 65535.0 / static_cast<double>(mx) : 0.0);
  if (!cv::imwrite(path, u)) throw std::runtime_error(path + ": cannot write");
}

}  // namespace photometric_out

// --integration: a modeling::Integration, or auto (poisson with --mask, else frankot-chellappa).
enum class IntegrationChoice { kAuto, kFrankotChellappa, kPoisson };
inline constexpr EnumTable<IntegrationChoice, 3> kIntegrationNames{
    {{IntegrationChoice::kAuto, "auto"},
     {IntegrationChoice::kFrankotChellappa, "frankot-chellappa"},
     {IntegrationChoice::kPoisson, "poisson"}}};
inline constexpr EnumTable<modeling::Rejection, 2> kRejectionNames{
    {{modeling::Rejection::kResidual, "residual"}, {modeling::Rejection::kBrightest, "brightest"}}};

struct PhotometricArgs {
  std::string images, lights = "dome", image_list, reference, mask, out, csv, tiff, normals, albedo;
  IntegrationChoice integration = IntegrationChoice::kAuto;
  modeling::Rejection rejection = modeling::Rejection::kResidual;
  double pitch = 0, shadow_fraction = 0.05, outlier_sigmas = 3, noise_floor = 1e-3,
         specular_fraction = 0.1;
  int min_lights = 4;
  bool y_up = false;
};

// The photographs: where they are, under which lights, and the pixels to solve.
void AddPhotometricInputs(CLI::App* cmd, PhotometricArgs& o) {
  cmd->add_option("--images", o.images,
                  "Folder of the images (any format OpenCV reads, plus TGA; linear response)")
      ->required();
  cmd->add_option(
         "--lights", o.lights,
         "Lights file, one light per line, comma and/or whitespace separated: 'file elevation_deg\n"
         "azimuth_deg' (azimuth from +x towards +y), 'file lx ly lz', or 'lx ly lz' with "
         "--image-list;\n"
         "optional first line with the count, optional header line; '#' lines ignored. Or 'dome'\n"
         "for the dissertation's 30-light dome with images light_00.png ... light_29.png")
      ->capture_default_str();
  cmd->add_option("--image-list", o.image_list,
                  "File names of the images, one per line in the lights' order (e.g. DiLiGenT's "
                  "filenames.txt)");
  cmd->add_flag("--lights-y-up", o.y_up,
                "The lights (and the normals written) use y up instead of y down the rows");
  cmd->add_option("--reference", o.reference,
                  "Folder of white-reference images (same names) for the radiance maps");
  cmd->add_option("--mask", o.mask,
                  "Mask image (any format above; non-zero = inside): outside pixels are neither "
                  "solved nor integrated");
  cmd->add_option("--pitch-m", o.pitch, "Pixel pitch on the sample [m]")
      ->required()
      ->check(CLI::PositiveNumber);
}

// How the normals are integrated and which readings each pixel's fit rejects.
void AddPhotometricSolverOptions(CLI::App* cmd, PhotometricArgs& o) {
  AddEnumOption(cmd, "--integration", o.integration, kIntegrationNames,
                "frankot-chellappa (periodic, FFT; whole image only), poisson (Neumann boundary: "
                "DCT on the\n"
                "whole image, sparse solve on a mask), or auto (poisson with --mask, else "
                "frankot-chellappa)");
  AddEnumOption(
      cmd, "--rejection", o.rejection, kRejectionNames,
      "residual (per pixel, from its Lambertian fit residuals) or brightest (the fixed rule:\n"
      "drop the brightest --specular-fraction of each pixel's lights)");
  cmd->add_option(
         "--outlier-sigmas", o.outlier_sigmas,
         "residual rule: a reading is an outlier beyond this many robust SDs of all residuals")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--shadow-fraction", o.shadow_fraction,
                  "readings darker than this fraction of the pixel's fitted brightness facing the "
                  "light are\n"
                  "shadows (brightest rule: of the pixel's brightest reading)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--noise-floor", o.noise_floor,
                  "residual rule: least residual SD, fraction of the facing brightness")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--min-lights", o.min_lights,
                  "residual rule: outlier rejection keeps at least this many lights")
      ->check(CLI::Range(3, 1000))
      ->capture_default_str();
  cmd->add_option("--specular-fraction", o.specular_fraction,
                  "brightest rule only: fraction of each pixel's lights dropped")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
}

void AddPhotometricOutputs(CLI::App* cmd, PhotometricArgs& o) {
  cmd->add_option("-o,--out", o.out, "Height map to write (.f32)")->required();
  cmd->add_option("--csv", o.csv, "Also write heights [m] as CSV (one image row per line)");
  cmd->add_option("--tiff", o.tiff, "Also write heights [m] as a 32-bit float TIFF");
  cmd->add_option("--normals", o.normals,
                  "Also write the normals: .png as 8-bit RGB = round(127.5 (n + 1)), .tif/.tiff as "
                  "32-bit float\n"
                  "RGB = (x, y, z); zero outside the mask");
  cmd->add_option(
      "--albedo", o.albedo,
      "Also write the albedo: .tif/.tiff as 32-bit float, .png as 16-bit scaled to its maximum");
}

// The option checks that need more than one option, before any image is read.
void CheckPhotometricArgs(const PhotometricArgs& o) {
  photometric_out::CheckImageOutput(o.normals, "--normals");
  photometric_out::CheckImageOutput(o.albedo, "--albedo");
  if (!o.mask.empty() && o.integration == IntegrationChoice::kFrankotChellappa)
    throw InputError(kCommandLine, 0, "--integration",
                     "frankot-chellappa integrates the whole image; with --mask use poisson");
}

// The lights, each with its image's name.
std::vector<modeling::Light> LoadNamedLights(const PhotometricArgs& o) {
  auto lights = modeling::LoadLights(o.lights, o.y_up);
  if (!o.image_list.empty()) modeling::ApplyImageList(o.image_list, lights);
  for (const auto& l : lights)
    if (l.file.empty())
      throw InputError(o.lights, l.line, "file", "no image name for this light: give --image-list");
  return lights;
}

modeling::PhotometricOptions PhotometricSolverOptions(const PhotometricArgs& o, int width,
                                                      int height) {
  modeling::PhotometricOptions po;
  po.pitch_m = o.pitch;
  po.integration = o.integration == IntegrationChoice::kPoisson ||
                           (o.integration == IntegrationChoice::kAuto && !o.mask.empty())
                       ? modeling::Integration::kPoisson
                       : modeling::Integration::kFrankotChellappa;
  po.rejection = o.rejection;
  po.shadow_fraction = o.shadow_fraction;
  po.outlier_sigmas = o.outlier_sigmas;
  po.noise_floor = o.noise_floor;
  po.min_lights = o.min_lights;
  po.specular_fraction = o.specular_fraction;
  if (!o.mask.empty()) po.mask = modeling::ReadMask(o.mask, width, height);
  return po;
}

// Reads the images (and the white references), solves, with a progress bar on a terminal.
modeling::PhotometricResult SolvePhotometric(const PhotometricArgs& o,
                                             const std::vector<modeling::Light>& lights,
                                             modeling::PhotometricOptions* po) {
  const auto images = modeling::ReadImages(o.images, lights);
  modeling::ImageStack ref;
  if (!o.reference.empty()) ref = modeling::ReadImages(o.reference, lights);
  if (!o.reference.empty() && (ref.width != images.width || ref.height != images.height))
    throw InputError(o.reference, 0, "", "the reference images differ in size from the images");
  *po = PhotometricSolverOptions(o, images.width, images.height);
  const bool tty = isatty(2);
  auto progress = [&](double f) {
    if (tty)
      fmt::print(stderr, "\rphotometric stereo [{:<40}] {:3.0f} %",
                 std::string(static_cast<std::size_t>(40 * f), '#'), 100 * f);
  };
  auto r = modeling::PhotometricStereo(images, lights, *po, o.reference.empty() ? nullptr : &ref,
                                       progress);
  if (tty) fmt::print(stderr, "\n");
  return r;
}

// The height map above its lowest point inside the mask (outside: 0) and its range [m].
std::vector<float> HeightsAboveLowest(const PhotometricArgs& o,
                                      const modeling::PhotometricResult& r, double* range_m) {
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
  for (std::size_t k = 0; k < r.height_m.size(); ++k)
    if (r.mask[k]) {
      lo = std::min(lo, r.height_m[k]);
      hi = std::max(hi, r.height_m[k]);
    }
  if (!(hi >= lo)) throw InputError(o.mask, 0, "", "the mask has no pixel inside");
  std::vector<float> h(r.height_m);
  for (auto& v : h) v -= lo;  // heights above the lowest point (outside the mask: 0)
  *range_m = static_cast<double>(hi - lo);
  return h;
}

// --out and its [geometry] table, then each "Also write" output asked for.
void WriteOutputs(const PhotometricArgs& o, const modeling::PhotometricResult& r,
                  std::vector<float>& h) {
  renderer::HeightMap(r.width, r.height, o.pitch, h).SaveRawF32(o.out);
  WriteTextFile(
      o.out + ".toml",
      fmt::format("[geometry]\nkind = \"file\"\nfile = \"{}\"\nwidth = {}\nheight = "
                  "{}\npitch_m = {:.10g}\n",
                  std::filesystem::path(o.out).filename().string(), r.width, r.height, o.pitch));
  if (!o.csv.empty()) {
    std::string csv;
    for (int i = 0; i < r.height; ++i)
      for (int j = 0; j < r.width; ++j)
        fmt::format_to(std::back_inserter(csv), "{:.9g}{}",
                       h[static_cast<std::size_t>(i) * static_cast<std::size_t>(r.width) +
                         static_cast<std::size_t>(j)],
                       j + 1 == r.width ? '\n' : ',');
    WriteTextFile(o.csv, csv);
  }
  if (!o.tiff.empty()) {
    cv::Mat m(r.height, r.width, CV_32F, h.data());
    if (!cv::imwrite(o.tiff, m)) throw std::runtime_error(o.tiff + ": cannot write TIFF");
  }
  if (!o.normals.empty()) photometric_out::WriteNormals(o.normals, r, o.y_up);
  if (!o.albedo.empty()) photometric_out::WriteAlbedo(o.albedo, r);
}

// What was written and solved, and a warning when the lights' frame looks mirrored.
void PrintPhotometricSummary(const PhotometricArgs& o, const modeling::PhotometricResult& r,
                             const modeling::PhotometricOptions& po, double range_m) {
  const std::size_t inside = static_cast<std::size_t>(std::count(r.mask.begin(), r.mask.end(), 1));
  fmt::print("{}x{} height map, range {:.3g} m -> {} (+ {}.toml)\n", r.width, r.height, range_m,
             o.out, o.out);
  fmt::print(
      "{} pixels solved{}{}; {}readings dropped: {:.1f} % bright (highlights), {:.1f} % dark "
      "(shadows)\n",
      inside - r.unsolved_pixels, o.mask.empty() ? "" : " inside the mask",
      r.unsolved_pixels
          ? fmt::format(" ({} more with fewer than 3 usable lights)", r.unsolved_pixels)
          : "",
      // Only the residual rule estimates the residuals' SD (the brightest rule never does).
      po.rejection == modeling::Rejection::kResidual
          ? fmt::format("residual SD {:.3g} of the brightness facing a light; ", r.residual_sd)
          : "",
      100 * r.dropped_bright, 100 * r.dropped_dark);
  if (r.axis_flip_suspected)
    fmt::print(stderr,
               "warning: the normals are {:.1f}x less integrable than with one image axis "
               "mirrored: the lights' frame\n"
               "  looks mirrored ({}). Frame: x along the columns, y {} the rows, z towards "
               "the camera.\n",
               r.mirrored_curl_ratio,
               o.y_up ? "lights written with y down? drop --lights-y-up"
                      : "lights written with y up? pass --lights-y-up",
               o.y_up ? "up" : "down");
}

int RunPhotometric(const PhotometricArgs& o) {
  CheckPhotometricArgs(o);
  const auto lights = LoadNamedLights(o);
  modeling::PhotometricOptions po;
  const auto r = SolvePhotometric(o, lights, &po);
  double range_m = 0;
  std::vector<float> h = HeightsAboveLowest(o, r, &range_m);
  WriteOutputs(o, r, h);
  PrintPhotometricSummary(o, r, po, range_m);
  return kExitOk;
}

}  // namespace

void AddPhotometric(CLI::App& model) {
  auto o = std::make_shared<PhotometricArgs>();
  auto* cmd = model.add_subcommand(
      "photometric",
      "Height map from photographs under known lights (photometric stereo, ch. IV.2): albedo and\n"
      "normals by alternating least squares on the Lambertian model, each pixel's shadowed and\n"
      "specular readings rejected from its own fit residuals, integrated by Frankot-Chellappa or "
      "a\n"
      "Poisson solve. Writes HEIGHT.f32 (the renderer's raw float32 metres) and HEIGHT.f32.toml\n"
      "(its [geometry] table for `model build`).\n"
      "Image frame: x along the columns (rightwards), y along the rows (DOWNWARDS, row 0 first),\n"
      "z up out of the sample towards the camera; light directions point towards the lights.\n"
      "Lights given with y up (x right, y up, z towards the camera) need --lights-y-up; a warning\n"
      "is printed when the normals look mirrored.");
  AddPhotometricInputs(cmd, *o);
  AddPhotometricSolverOptions(cmd, *o);
  AddPhotometricOutputs(cmd, *o);
  cmd->callback([o] { RunGuarded([&] { return RunPhotometric(*o); }); });
}

}  // namespace hapticlab::cli
