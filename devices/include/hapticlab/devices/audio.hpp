#pragma once
/// @file The `audio` back-end: the vibrotactile actuator (a voice coil such as the Haptuator,
/// through an audio amplifier) and the masking noise on the participant's headphones, both
/// on one sound device (one stream) through PortAudio. By default (AudioConfig::pull) the
/// audio callback pulls acceleration samples at the input rate from the engine's
/// SampleSource, so the sound card's clock paces the vibration synthesis; otherwise the
/// vibration loop writes them at its own rate into a lock-free queue. Either way the callback
/// upsamples to the device's rate, maps channels, adds white noise on the headphone
/// channels, and counts underflows and clipping. The host API is behind AudioStream so tests drive
/// the callback themselves.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/spsc_queue.hpp"
#include "hapticlab/devices/device.hpp"

namespace hapticlab::devices {

struct AudioConfig {
  std::string device;             ///< PortAudio device name (substring); empty: the default output
  double sample_rate_hz = 48000;  ///< the sound device's rate
  double input_rate_hz = 10000;   ///< rate of the samples the vibration loop writes
  double latency_s = 0.005;       ///< suggested output latency
  int channels = 2;
  std::vector<int> actuator_channels{0};  ///< channels that carry the actuator signal
  std::vector<int> noise_channels{1};     ///< headphone channels that carry white noise
  double full_scale_mps2 = 50;  ///< acceleration at full scale (amplifier and actuator calibration)
  double noise_rms_fs = 0.1;    ///< masking noise level (RMS, full-scale units)
  double queue_s = 0.05;        ///< buffer between the vibration loop and the callback
  std::uint64_t seed = 1;       ///< noise seed (recorded with the session)
  /// true: the callback pulls input samples from the engine's source (SetSource): the sound
  /// card's clock paces the vibration synthesis and there is no queue to underrun. false:
  /// the vibration loop pushes through a queue (Write).
  bool pull = true;
};
/// Checks channel indices, rates and levels. The values are the user's (command-line options,
/// a rig's settings): @throws InputError on `source` (the file they came from, or
/// "<command line>"), line 0, naming the AudioConfig member at fault and what was expected.
void ValidateAudioConfig(const AudioConfig& c, const std::string& source = "<command line>");

/// The host API seam: starts a stream that calls `render` with interleaved float frames.
class AudioStream {
 public:
  using Render = std::function<void(float* interleaved, unsigned long frames)>;
  virtual ~AudioStream() = default;
  virtual void Start(const AudioConfig& c, Render render) = 0;
  virtual void Stop() = 0;
  virtual std::string Describe() const = 0;  ///< device and actual latency, for provenance
};
/// PortAudio output stream. @throws std::runtime_error when the device cannot be opened.
std::unique_ptr<AudioStream> OpenPortAudio();
/// The output devices PortAudio sees ("index: name (channels, default rate)").
std::vector<std::string> ListAudioDevices();

class AudioOutput final : public Actuator, public MaskingNoise {
 public:
  AudioOutput(const AudioConfig& c, std::unique_ptr<AudioStream> stream);
  ~AudioOutput() override;
  double SampleRateHz() const override { return c_.input_rate_hz; }
  /// Vibration loop: queue one sample [m/s^2]; a full queue drops it (counted).
  void Write(double acc_mps2) noexcept override;
  void SetNoiseLevel(double rms_fs) noexcept override {
    noise_rms_.store(rms_fs, std::memory_order_relaxed);
  }
  bool PullsSamples() const noexcept override { return c_.pull; }
  void SetSource(devices::SampleSource* source) noexcept override;
  void Start();
  void Stop();
  /// The audio callback's body (public for tests): fills `frames` interleaved frames.
  void Render(float* out, unsigned long frames) noexcept;

  std::uint64_t underflows() const { return underflows_.load(); }  ///< output samples with no input
  std::uint64_t Underruns() const noexcept override {
    return underflows_.load(std::memory_order_relaxed);
  }
  std::uint64_t overflows() const { return overflows_.load(); }  ///< input samples dropped
  std::uint64_t clipped() const { return clipped_.load(); }  ///< output samples beyond full scale

 private:
  AudioConfig c_;
  std::unique_ptr<AudioStream> stream_;
  SpscQueue<float> queue_;
  std::atomic<double> noise_rms_;
  Rng noise_;
  double phase_ = 0, prev_ = 0, cur_ = 0, step_;  // one input sample of latency (interpolation)
  std::vector<char> is_actuator_, is_noise_;
  std::atomic<std::uint64_t> underflows_{0}, overflows_{0}, clipped_{0};
  std::atomic<devices::SampleSource*> source_{nullptr};
  std::atomic<bool> in_render_{false};
  bool started_ = false;
};

}  // namespace hapticlab::devices
