#pragma once
/// @file DFT321 (Landin, Romano, McMahan, Kuchenbecker, EuroHaptics 2010): three (or any
/// number of) acceleration axes reduced to one signal with the same energy at every
/// frequency, as the Penn Haptic Texture Toolkit reduces its recordings. Per DFT bin k:
///   |A(k)| = sqrt(sum_i |A_i(k)|^2),   angle A(k) = angle(sum_i A_i(k)),
/// and the reduced signal is the inverse DFT of A. Written from that definition with FFTW.

#include <cstddef>
#include <memory>
#include <vector>

namespace hapticlab::modeling {

/// DFT321 of whole signals: one DFT of each axis's full length (all axes equally long, at
/// least one). A bin where the axes' spectra sum to zero takes phase 0.
std::vector<double> Dft321(const std::vector<std::vector<double>>& axes);

/// DFT321 of a stream, for recordings too long to transform whole: frames of `frame`
/// samples (even) with 50 % overlap, each axis windowed by a periodic sqrt-Hann window before
/// its DFT and the reduced frame windowed again and overlap-added (the squared windows sum to
/// one, so a single axis comes back unchanged). Memory: a few frames plus the output.
class Dft321Stream {
 public:
  Dft321Stream(int axes, std::size_t frame = std::size_t{1} << 15);
  ~Dft321Stream();
  Dft321Stream(const Dft321Stream&) = delete;
  Dft321Stream& operator=(const Dft321Stream&) = delete;
  /// Appends `frames` samples of every axis, interleaved with `stride` values per frame;
  /// axis a is at column `columns[a]`.
  void Push(const double* data, std::size_t frames, int stride, const int* columns);
  /// Flushes the last frames and returns the reduced signal (as long as the input).
  std::vector<double> Finish();

 private:
  void Transform();
  int axes_;
  std::size_t n_, hop_, filled_ = 0, pushed_ = 0, frames_done_ = 0;
  std::vector<std::vector<double>> buf_;  // the current frame of each axis
  std::vector<double> window_, out_, acc_;
  struct Fft;
  std::unique_ptr<Fft> fft_;
};

}  // namespace hapticlab::modeling
