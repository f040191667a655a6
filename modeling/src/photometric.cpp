#include "hapticlab/modeling/photometric.hpp"

#include <fftw3.h>
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <mutex>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"

namespace hapticlab::modeling {
namespace {

constexpr double kPi = std::numbers::pi;

Eigen::Vector3d FromAngles(double elev_deg, double azim_deg) {
  const double e = elev_deg * kPi / 180, a = azim_deg * kPi / 180;
  return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

}  // namespace

std::vector<Light> DomePreset() {
  std::vector<Light> l;
  int k = 0;
  for (double e : {40.0, 55.0, 70.0})
    for (int a = 0; a < 10; ++a) l.push_back({fmt::format("light_{:02d}.png", k++), FromAngles(e, 36.0 * a)});
  return l;
}

std::vector<Light> LoadLights(const std::string& path) {
  if (path == "dome") return DomePreset();
  std::string text = ReadTextFile(path, "lights file");
  const bool has_header = text.rfind("file", 0) == 0;
  const auto first_line = text.substr(0, text.find('\n'));
  const auto fields = std::count(first_line.begin(), first_line.end(), ',');
  if (!has_header) text = (fields == 2 ? "file,elevation_deg,azimuth_deg\n" : "file,lx,ly,lz\n") + text;
  const auto t = ParseCsv(text, path);
  std::vector<Light> out;
  const bool angles = t.header.size() == 3;
  if (t.header.size() != 3 && t.header.size() != 4)
    throw InputError(path, 1, "", "expected file,elevation_deg,azimuth_deg or file,lx,ly,lz");
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    Light l;
    l.file = t.rows[r][0];
    if (angles) {
      l.direction = FromAngles(t.Number(r, 1), t.Number(r, 2));
    } else {
      l.direction = Eigen::Vector3d(t.Number(r, 1), t.Number(r, 2), t.Number(r, 3));
      if (!(l.direction.norm() > 0)) throw InputError(path, t.row_lines[r], "lx", "zero light direction");
      l.direction.normalize();
    }
    if (!(l.direction.z() > 0)) throw InputError(path, t.row_lines[r], "", "light below the sample plane");
    out.push_back(l);
  }
  if (out.size() < 3) throw InputError(path, 0, "", "photometric stereo needs at least 3 lights");
  return out;
}

ImageStack ReadImages(const std::string& dir, const std::vector<Light>& lights) {
  ImageStack s;
  for (const auto& l : lights) {
    const std::string path = (std::filesystem::path(dir) / l.file).string();
    cv::Mat m = cv::imread(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_GRAYSCALE);
    if (m.empty()) throw InputError(path, 0, "", "cannot read image (8- or 16-bit PNG or TIFF expected)");
    cv::Mat f;
    const double scale = m.depth() == CV_16U ? 1.0 / 65535 : m.depth() == CV_8U ? 1.0 / 255 : 1.0;
    m.convertTo(f, CV_32F, scale);
    if (s.images.empty()) {
      s.width = f.cols;
      s.height = f.rows;
    } else if (f.cols != s.width || f.rows != s.height) {
      throw InputError(path, 0, "", fmt::format("image is {}x{}, the first was {}x{}", f.cols, f.rows, s.width, s.height));
    }
    s.images.emplace_back(f.ptr<float>(), f.ptr<float>() + static_cast<std::size_t>(s.width) * static_cast<std::size_t>(s.height));
  }
  return s;
}

PhotometricResult PhotometricStereo(const ImageStack& st, const std::vector<Light>& lights, const PhotometricOptions& o,
                                    const ImageStack* ref, const std::function<void(double)>& progress) {
  const std::size_t m = lights.size(), npx = static_cast<std::size_t>(st.width) * static_cast<std::size_t>(st.height);
  if (st.images.size() != m) throw std::invalid_argument("one image per light is needed");
  if (m < 3) throw std::invalid_argument("photometric stereo needs at least 3 lights");
  PhotometricResult r;
  r.width = st.width;
  r.height = st.height;
  r.albedo.assign(npx, 0.f);
  r.normals.assign(npx, Eigen::Vector3f::UnitZ());
  r.light_scale.assign(m, 1.0);
  std::vector<float> inten(npx * m);  // pixel-major copy, flat-field corrected
  for (std::size_t j = 0; j < m; ++j)
    for (std::size_t i = 0; i < npx; ++i) {
      float v = st.images[j][i];
      if (ref) v = ref->images[j][i] > 1e-6f ? v / ref->images[j][i] : 0.f;
      inten[i * m + j] = v;
    }
  std::vector<Eigen::Vector3d> b(npx, Eigen::Vector3d::Zero());
  std::vector<std::uint8_t> use(npx * m, 0);
  // Masks: shadows (dark) and speculars (brightest few) are excluded per pixel.
  for (std::size_t i = 0; i < npx; ++i) {
    const float* I = &inten[i * m];
    const float mx = *std::max_element(I, I + m);
    std::vector<std::size_t> idx;
    for (std::size_t j = 0; j < m; ++j)
      if (I[j] > o.shadow_fraction * mx) idx.push_back(j);
    std::sort(idx.begin(), idx.end(), [&](auto a, auto c) { return I[a] < I[c]; });
    const std::size_t drop = idx.size() >= 6 ? static_cast<std::size_t>(std::floor(o.specular_fraction * static_cast<double>(idx.size()))) : 0;
    for (std::size_t k = 0; k + drop < idx.size(); ++k) use[i * m + idx[k]] = 1;
  }
  for (int it = 0; it < o.iterations; ++it) {
    // (a) per pixel: b = argmin sum_j (I_j - s_j l_j . b)^2 over the usable lights.
    for (std::size_t i = 0; i < npx; ++i) {
      Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
      Eigen::Vector3d y = Eigen::Vector3d::Zero();
      int count = 0;
      for (std::size_t j = 0; j < m; ++j) {
        if (!use[i * m + j]) continue;
        const Eigen::Vector3d l = r.light_scale[j] * lights[j].direction;
        A += l * l.transpose();
        y += l * inten[i * m + j];
        ++count;
      }
      b[i] = count >= 3 && std::abs(A.determinant()) > 1e-12 ? Eigen::Vector3d(A.ldlt().solve(y)) : Eigen::Vector3d::Zero();
      if (progress && i % 65536 == 0) progress((it + 0.5 * static_cast<double>(i) / static_cast<double>(npx)) / o.iterations);
    }
    // (b) per light: s_j = argmin sum_i (I_ij - s_j l_j . b_i)^2, normalized to mean 1.
    double mean = 0;
    for (std::size_t j = 0; j < m; ++j) {
      double num = 0, den = 0;
      for (std::size_t i = 0; i < npx; ++i) {
        if (!use[i * m + j]) continue;
        const double pred = lights[j].direction.dot(b[i]);
        num += pred * inten[i * m + j];
        den += pred * pred;
      }
      r.light_scale[j] = den > 0 ? num / den : 1.0;
      mean += r.light_scale[j];
    }
    mean /= static_cast<double>(m);
    for (auto& s : r.light_scale) s /= mean;
    if (progress) progress((it + 1.0) / o.iterations);
  }
  for (std::size_t i = 0; i < npx; ++i) {
    const double a = b[i].norm();
    r.albedo[i] = static_cast<float>(a);
    if (a > 0 && b[i].z() > 0) r.normals[i] = (b[i] / a).cast<float>();
  }
  r.height_m = o.integration == Integration::kPoisson ? IntegrateNormalsPoisson(r.normals, r.width, r.height, o.pitch_m)
                                                      : IntegrateNormals(r.normals, r.width, r.height, o.pitch_m);
  return r;
}

std::vector<float> IntegrateNormals(const std::vector<Eigen::Vector3f>& nrm, int w, int h, double pitch) {
  const int wc = w / 2 + 1;
  static std::mutex mu;  // FFTW planning is not thread-safe
  std::vector<double> p(static_cast<std::size_t>(w) * static_cast<std::size_t>(h)), q(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const auto& n = nrm[i];
    const double nz = std::max(static_cast<double>(n.z()), 1e-3);
    p[i] = -n.x() / nz;  // dh/dx (height units per pixel unit)
    q[i] = -n.y() / nz;  // dh/dy
  }
  std::vector<std::complex<double>> P(static_cast<std::size_t>(h) * static_cast<std::size_t>(wc)), Q(P.size()), Z(P.size());
  std::vector<double> out(p.size());
  fftw_plan fp, fq, iz;
  {
    std::lock_guard lock(mu);
    fp = fftw_plan_dft_r2c_2d(h, w, p.data(), reinterpret_cast<fftw_complex*>(P.data()), FFTW_ESTIMATE);
    fq = fftw_plan_dft_r2c_2d(h, w, q.data(), reinterpret_cast<fftw_complex*>(Q.data()), FFTW_ESTIMATE);
    iz = fftw_plan_dft_c2r_2d(h, w, reinterpret_cast<fftw_complex*>(Z.data()), out.data(), FFTW_ESTIMATE);
  }
  fftw_execute(fp);
  fftw_execute(fq);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < wc; ++u) {
      const double wx = 2 * kPi * u / w, wy = 2 * kPi * (v <= h / 2 ? v : v - h) / h;
      const std::size_t k = static_cast<std::size_t>(v) * static_cast<std::size_t>(wc) + static_cast<std::size_t>(u);
      const double d = wx * wx + wy * wy;
      Z[k] = d > 0 ? (std::complex<double>(0, -wx) * P[k] + std::complex<double>(0, -wy) * Q[k]) / d : 0.0;
    }
  fftw_execute(iz);
  {
    std::lock_guard lock(mu);
    fftw_destroy_plan(fp);
    fftw_destroy_plan(fq);
    fftw_destroy_plan(iz);
  }
  std::vector<float> hgt(out.size());
  const double norm = static_cast<double>(w) * static_cast<double>(h);
  for (std::size_t i = 0; i < out.size(); ++i) hgt[i] = static_cast<float>(out[i] / norm * pitch);
  return hgt;
}

std::vector<float> IntegrateNormalsPoisson(const std::vector<Eigen::Vector3f>& nrm, int w, int h, double pitch) {
  // Divergence of the gradient field with backward differences (zero gradient outside), the
  // discrete Laplacian with Neumann boundary diagonalised by the DCT-II [Simchony,
  // Chellappa, Shao 1990, doi:10.1109/34.55103].
  const auto W = static_cast<std::size_t>(w), H = static_cast<std::size_t>(h);
  std::vector<double> p(W * H), q(W * H), f(W * H), z(W * H);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double nz = std::max(static_cast<double>(nrm[i].z()), 1e-3);
    p[i] = -nrm[i].x() / nz;
    q[i] = -nrm[i].y() / nz;
  }
  for (std::size_t i = 0; i < H; ++i)
    for (std::size_t j = 0; j < W; ++j) {
      const std::size_t k = i * W + j;
      const double px = (j + 1 < W ? p[k] : 0.0) - (j > 0 ? p[k - 1] : 0.0);
      const double qy = (i + 1 < H ? q[k] : 0.0) - (i > 0 ? q[k - W] : 0.0);
      f[k] = px + qy;
    }
  static std::mutex mu;
  fftw_plan fwd, inv;
  {
    std::lock_guard lock(mu);
    fwd = fftw_plan_r2r_2d(h, w, f.data(), z.data(), FFTW_REDFT10, FFTW_REDFT10, FFTW_ESTIMATE);
    inv = fftw_plan_r2r_2d(h, w, z.data(), f.data(), FFTW_REDFT01, FFTW_REDFT01, FFTW_ESTIMATE);
  }
  fftw_execute(fwd);
  for (std::size_t i = 0; i < H; ++i)
    for (std::size_t j = 0; j < W; ++j) {
      const double lam = 2 * std::cos(kPi * static_cast<double>(j) / w) + 2 * std::cos(kPi * static_cast<double>(i) / h) - 4;
      z[i * W + j] = (i == 0 && j == 0) ? 0.0 : z[i * W + j] / lam;
    }
  fftw_execute(inv);
  {
    std::lock_guard lock(mu);
    fftw_destroy_plan(fwd);
    fftw_destroy_plan(inv);
  }
  std::vector<float> out(W * H);
  const double norm = 4.0 * static_cast<double>(W) * static_cast<double>(H);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = static_cast<float>(f[i] / norm * pitch);
  return out;
}

}  // namespace hapticlab::modeling
