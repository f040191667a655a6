#pragma once
/// @file Band-limited upsampling by an integer factor L (polyphase form): a Hann-windowed
/// sinc low-pass with its cut-off at the input's Nyquist frequency, `taps_per_phase * L`
/// taps at the output rate, split into L branches of `taps_per_phase` taps, each normalised
/// to unit DC gain. Output sample m L + p is sum_j x[m - j] h[p + j L]. With 32 taps per
/// phase (the vibration loop's choice) the response is flat within 0.1 dB up to 0.45 f_in,
/// -0.9 dB at 0.47, -3.7 dB at 0.49, -6 dB at 0.5 f_in (any interpolator whose images are
/// suppressed must roll off at f_in / 2), and images from 0.55 f_in on are 44 dB down.
/// Linear interpolation (the alternative) has the response sinc^2(f / f_in): -1.3 dB at 0.3,
/// -3.1 dB at 0.45 f_in, and the image of a tone at 0.45 f_in only 3.5 dB below it
/// (tests/renderer/upsampler_test.cpp). Group delay: (taps_per_phase L - 1) / (2 L) input
/// samples. Push and Output are noexcept and allocation-free (buffers sized in the
/// constructor).

#include <vector>

namespace hapticlab::renderer {

class PolyphaseUpsampler {
 public:
  PolyphaseUpsampler() = default;
  /// @param factor L >= 1 (1: the output is the newest input)
  /// @param taps_per_phase >= 1
  /// @throws PreconditionError on factor < 1 or taps_per_phase < 1
  PolyphaseUpsampler(int factor, int taps_per_phase);

  /// Takes the next input sample; call it before the L outputs of its period.
  void Push(double x) noexcept {
    head_ = head_ == 0 ? taps_ - 1 : head_ - 1;
    const auto h = static_cast<std::size_t>(head_);
    hist_[h] = hist_[h + static_cast<std::size_t>(taps_)] = x;
  }
  /// Output sample of phase p (0 <= p < factor) of the current input period.
  double Output(int phase) const noexcept {
    if (factor_ == 1) return hist_[static_cast<std::size_t>(head_)];
    const double* x = hist_.data() + head_;
    const double* h = h_.data() + static_cast<std::size_t>(phase) * static_cast<std::size_t>(taps_);
    double y = 0;
    for (int j = 0; j < taps_; ++j) y += x[j] * h[j];
    return y;
  }
  void Reset() noexcept;

  int factor() const { return factor_; }
  int taps_per_phase() const { return taps_; }
  /// Group delay in input samples.
  double DelayInputSamples() const {
    return factor_ == 1 ? 0.0 : 0.5 * (taps_ * factor_ - 1) / factor_;
  }

 private:
  int factor_ = 1, taps_ = 1;
  std::vector<double> h_;     // h_[p * taps + j] = h[p + j L]
  std::vector<double> hist_;  // newest-first inputs, doubled ring: [head, head + taps)
  int head_ = 0;
};

}  // namespace hapticlab::renderer
