#pragma once
// Synthetic photometric-stereo scenes shared by photometric_test.cpp and
// normal_integration_test.cpp: height fields with analytic normals, a sphere, light sets and
// Lambertian images rendered from them (image frame: x = column, y = row downwards, z up).

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <vector>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/modeling/photometric.hpp"

namespace hapticlab::modeling::scenes {

constexpr double kPi = std::numbers::pi;
constexpr int kN = 128;           // image size
constexpr double kPitch = 20e-6;  // m per pixel

struct Field {
  std::vector<double> h;           // metres
  std::vector<Eigen::Vector3f> n;  // true normals
};

// Height field with analytic gradient, sampled on the grid.
inline Field Make(const std::function<double(double, double)>& h,
                  const std::function<Eigen::Vector2d(double, double)>& g) {
  Field f;
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) {
      const double x = j * kPitch, y = i * kPitch;
      f.h.push_back(h(x, y));
      const auto d = g(x, y);
      f.n.push_back(Eigen::Vector3d(-d.x(), -d.y(), 1).normalized().cast<float>());
    }
  return f;
}

// h = A sin(2 pi x / lx) cos(2 pi y / ly): periodic over the image when lx and ly divide it.
inline Field Sinusoid(double A, double lx, double ly) {
  return Make([=](double x,
                  double y) { return A * std::sin(2 * kPi * x / lx) * std::cos(2 * kPi * y / ly); },
              [=](double x, double y) {
                return Eigen::Vector2d(
                    A * 2 * kPi / lx * std::cos(2 * kPi * x / lx) * std::cos(2 * kPi * y / ly),
                    -A * 2 * kPi / ly * std::sin(2 * kPi * x / lx) * std::sin(2 * kPi * y / ly));
              });
}

// Lambertian images under the dome, relative noise `noise`, optional shadowed lights.
inline ImageStack Render(const Field& f, const std::vector<Light>& L, double noise,
                         std::uint64_t seed, int shadowed = 0) {
  Rng rng(seed);
  ImageStack s;
  s.width = s.height = kN;
  for (std::size_t j = 0; j < L.size(); ++j) {
    std::vector<float> img(f.n.size());
    for (std::size_t i = 0; i < img.size(); ++i) {
      const double v = 0.8 * std::max(0.0, L[j].direction.dot(f.n[i].cast<double>()));
      img[i] = static_cast<float>(v * (1 + noise * rng.Normal()));
      // Cast shadows: the first `shadowed` lights are blocked on the left half.
      if (static_cast<int>(j) < shadowed && (i % kN) < kN / 2) img[i] = 0;
    }
    s.images.push_back(img);
  }
  return s;
}

struct Errors {
  double mean_angle_deg, height_rms_fraction;
};

inline Errors Compare(const Field& f, const PhotometricResult& r) {
  double ang = 0;
  for (std::size_t i = 0; i < f.n.size(); ++i)
    ang += std::acos(std::clamp(static_cast<double>(f.n[i].dot(r.normals[i])), -1.0, 1.0));
  double mt = 0, me = 0, lo = 1e300, hi = -1e300;
  for (std::size_t i = 0; i < f.h.size(); ++i) {
    mt += f.h[i];
    me += r.height_m[i];
    lo = std::min(lo, f.h[i]);
    hi = std::max(hi, f.h[i]);
  }
  mt /= static_cast<double>(f.h.size());
  me /= static_cast<double>(f.h.size());
  double se = 0;
  for (std::size_t i = 0; i < f.h.size(); ++i)
    se += std::pow((r.height_m[i] - me) - (f.h[i] - mt), 2);
  return {ang / static_cast<double>(f.n.size()) * 180 / kPi,
          std::sqrt(se / static_cast<double>(f.h.size())) / (hi - lo)};
}

// A sphere of radius R pixels centred in an n x n image, seen from above; `mask` is the disk
// of radius mask_frac * R. Normals in the image frame (x = column, y = row downwards).
struct Sphere {
  int n = 0;
  double R = 0;
  std::vector<Eigen::Vector3f> normals;  // (0, 0, 1) off the sphere
  std::vector<double> height;            // pixels, 0 off the sphere
  std::vector<std::uint8_t> mask;
};

inline Sphere MakeSphere(int n, double R, double mask_frac) {
  Sphere s;
  s.n = n;
  s.R = R;
  const double c = (n - 1) / 2.0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double x = j - c, y = i - c, r2 = x * x + y * y;
      if (r2 < R * R) {
        const double z = std::sqrt(R * R - r2);
        s.normals.push_back(Eigen::Vector3d(x, y, z).normalized().cast<float>());
        s.height.push_back(z);
      } else {
        s.normals.push_back(Eigen::Vector3f::UnitZ());
        s.height.push_back(0);
      }
      s.mask.push_back(r2 < mask_frac * mask_frac * R * R ? 1 : 0);
    }
  return s;
}

// Twelve lights: four each at elevations 45°, 60° and 75°.
inline std::vector<Light> TwelveLights() {
  std::vector<Light> L;
  const double el[3] = {45, 60, 75}, az0[3] = {0, 45, 0};
  for (int e = 0; e < 3; ++e)
    for (int a = 0; a < 4; ++a) {
      const double el_r = el[e] * kPi / 180, az = (az0[e] + 90.0 * a) * kPi / 180;
      L.push_back({"",
                   Eigen::Vector3d(std::cos(el_r) * std::cos(az), std::cos(el_r) * std::sin(az),
                                   std::sin(el_r)),
                   0});
    }
  return L;
}

// Images of the sphere (a varying albedo, per-light intensities 0.8-1.2, attached shadows),
// optionally with a Blinn-Phong highlight k_s (n.h)^shininess, h = (l + v)/|l + v|, v = +z;
// noise: 1 % relative plus 0.001 absolute; clipped to [0, 1] like a sensor. Off the sphere:
// a black background (noise only).
inline ImageStack RenderSphere(const Sphere& s, const std::vector<Light>& L, double k_s,
                               double shininess, std::uint64_t seed) {
  Rng rng(seed);
  ImageStack st;
  st.width = st.height = s.n;
  for (std::size_t j = 0; j < L.size(); ++j) {
    const double scale = 0.8 + 0.4 * static_cast<double>((j * 7) % 12) / 11.0;
    const Eigen::Vector3d hv = (L[j].direction + Eigen::Vector3d::UnitZ()).normalized();
    std::vector<float> img(s.normals.size());
    for (std::size_t i = 0; i < img.size(); ++i) {
      const Eigen::Vector3d nn = s.normals[i].cast<double>();
      const bool on = s.height[i] > 0;
      const double rho =
          0.45 + 0.25 * std::sin(0.21 * static_cast<double>(i % static_cast<std::size_t>(s.n))) *
                     std::cos(0.17 * static_cast<double>(i / static_cast<std::size_t>(s.n)));
      const double ndl = L[j].direction.dot(nn);
      double v = on ? scale * rho * std::max(0.0, ndl) : 0.0;
      if (on && ndl > 0 && k_s > 0)
        v += scale * k_s * std::pow(std::max(0.0, nn.dot(hv)), shininess);
      v = v * (1 + 0.01 * rng.Normal()) + 0.001 * rng.Normal();
      img[i] = static_cast<float>(std::clamp(v, 0.0, 1.0));
    }
    st.images.push_back(std::move(img));
  }
  return st;
}

inline double AngleDeg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  return std::acos(std::clamp(static_cast<double>(a.normalized().dot(b.normalized())), -1.0, 1.0)) *
         180 / kPi;
}

inline double MedianErrorDeg(const Sphere& s, const std::vector<Eigen::Vector3f>& n) {
  std::vector<double> e;
  for (std::size_t i = 0; i < n.size(); ++i)
    if (s.mask[i]) e.push_back(AngleDeg(s.normals[i], n[i]));
  std::nth_element(e.begin(), e.begin() + static_cast<std::ptrdiff_t>(e.size() / 2), e.end());
  return e[e.size() / 2];
}

}  // namespace hapticlab::modeling::scenes
