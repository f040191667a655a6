// DFT321 (dft321.hpp): whole-signal and streaming forms, from the definition in Landin et
// al. (2010). Hand-written because no Debian package provides it; the DFTs are FFTW's.
#include "hapticlab/modeling/dft321.hpp"

#include <fftw3.h>

#include <cmath>
#include <complex>
#include <mutex>
#include <numbers>
#include <stdexcept>

#include "hapticlab/core/status.hpp"

namespace hapticlab::modeling {
namespace {

std::mutex& PlannerMutex() {  // FFTW's planner is not thread-safe
  static std::mutex mu;
  return mu;
}

// One real DFT size: forward for each axis, the combination, the inverse.
class RealDft {
 public:
  explicit RealDft(std::size_t n)
      : n_(n), in_(fftw_alloc_real(n)), spec_(fftw_alloc_complex(n / 2 + 1)) {
    std::lock_guard lock(PlannerMutex());
    fwd_ = fftw_plan_dft_r2c_1d(static_cast<int>(n), in_, spec_, FFTW_ESTIMATE);
    inv_ = fftw_plan_dft_c2r_1d(static_cast<int>(n), spec_, in_, FFTW_ESTIMATE);
  }
  ~RealDft() {
    {
      std::lock_guard lock(PlannerMutex());
      fftw_destroy_plan(fwd_);
      fftw_destroy_plan(inv_);
    }
    fftw_free(in_);
    fftw_free(spec_);
  }
  RealDft(const RealDft&) = delete;
  RealDft& operator=(const RealDft&) = delete;
  double* in() { return in_; }
  std::size_t bins() const { return n_ / 2 + 1; }
  // Spectrum of in() added into sum (complex) and its power into power.
  void Accumulate(std::vector<std::complex<double>>& sum, std::vector<double>& power) {
    fftw_execute(fwd_);
    for (std::size_t k = 0; k < bins(); ++k) {
      const std::complex<double> c(spec_[k][0], spec_[k][1]);
      sum[k] += c;
      power[k] += std::norm(c);
    }
  }
  // in() = inverse DFT of sqrt(power) at the phase of sum (scaled by 1/n).
  void Combine(const std::vector<std::complex<double>>& sum, const std::vector<double>& power) {
    for (std::size_t k = 0; k < bins(); ++k) {
      const double mag = std::sqrt(power[k]), a = std::abs(sum[k]);
      const std::complex<double> c = a > 0 ? sum[k] * (mag / a) : std::complex<double>(mag, 0);
      spec_[k][0] = c.real();
      spec_[k][1] = c.imag();
    }
    fftw_execute(inv_);
    for (std::size_t i = 0; i < n_; ++i) in_[i] /= static_cast<double>(n_);
  }

 private:
  std::size_t n_;
  double* in_;
  fftw_complex* spec_;
  fftw_plan fwd_, inv_;
};

}  // namespace

std::vector<double> Dft321(const std::vector<std::vector<double>>& axes) {
  HL_REQUIRE(!axes.empty(), "DFT321 needs at least one axis");
  const std::size_t n = axes[0].size();
  for (const auto& a : axes) HL_REQUIRE(a.size() == n, "DFT321: the axes differ in length");
  if (n < 2) return n == 1 ? std::vector<double>{axes[0][0]} : std::vector<double>{};
  RealDft dft(n);
  std::vector<std::complex<double>> sum(dft.bins());
  std::vector<double> power(dft.bins(), 0.0);
  for (const auto& a : axes) {
    std::copy(a.begin(), a.end(), dft.in());
    dft.Accumulate(sum, power);
  }
  dft.Combine(sum, power);
  return {dft.in(), dft.in() + n};
}

struct Dft321Stream::Fft {
  explicit Fft(std::size_t n) : dft(n) {}
  RealDft dft;
};

Dft321Stream::Dft321Stream(int axes, std::size_t frame)
    : axes_(axes), n_(frame), hop_(frame / 2), fft_(std::make_unique<Fft>(frame)) {
  HL_REQUIRE(axes >= 1 && frame >= 4 && frame % 2 == 0,
             "DFT321 stream: at least one axis and an even frame >= 4");
  buf_.assign(static_cast<std::size_t>(axes), std::vector<double>(n_, 0.0));
  window_.resize(n_);
  for (std::size_t i = 0; i < n_; ++i)  // periodic sqrt-Hann: w^2 + w^2(shifted by n/2) = 1
    window_[i] = std::sin(std::numbers::pi * static_cast<double>(i) / static_cast<double>(n_));
  acc_.assign(n_, 0.0);
  filled_ = hop_;  // a half frame of zeros first, so every sample lies in two frames
}

Dft321Stream::~Dft321Stream() = default;

void Dft321Stream::Transform() {
  RealDft& dft = fft_->dft;
  std::vector<std::complex<double>> sum(dft.bins());
  std::vector<double> power(dft.bins(), 0.0);
  for (const auto& b : buf_) {
    for (std::size_t i = 0; i < n_; ++i) dft.in()[i] = window_[i] * b[i];
    dft.Accumulate(sum, power);
  }
  dft.Combine(sum, power);
  for (std::size_t i = 0; i < n_; ++i) acc_[i] += window_[i] * dft.in()[i];
  // The first hop of the accumulator is complete; the very first is the zero prefix.
  if (frames_done_++ > 0) out_.insert(out_.end(), acc_.begin(), acc_.begin() + hop_);
  std::copy(acc_.begin() + hop_, acc_.end(), acc_.begin());
  std::fill(acc_.begin() + hop_, acc_.end(), 0.0);
  for (auto& b : buf_) std::copy(b.begin() + hop_, b.end(), b.begin());
  filled_ = hop_;
}

void Dft321Stream::Push(const double* data, std::size_t frames, int stride, const int* columns) {
  for (std::size_t f = 0; f < frames; ++f) {
    for (int a = 0; a < axes_; ++a)
      buf_[static_cast<std::size_t>(a)][filled_] =
          data[f * static_cast<std::size_t>(stride) + static_cast<std::size_t>(columns[a])];
    ++pushed_;
    if (++filled_ == n_) Transform();
  }
}

std::vector<double> Dft321Stream::Finish() {
  const std::vector<double> zeros(static_cast<std::size_t>(axes_), 0.0);
  std::vector<int> cols(static_cast<std::size_t>(axes_));
  for (int a = 0; a < axes_; ++a) cols[static_cast<std::size_t>(a)] = a;
  const std::size_t real = pushed_;
  while (out_.size() < real) Push(zeros.data(), 1, axes_, cols.data());
  out_.resize(real);
  pushed_ = real;
  return std::move(out_);
}

}  // namespace hapticlab::modeling
