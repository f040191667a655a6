#include "hapticlab/devices/audio.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <portaudio.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <stdexcept>

namespace hapticlab::devices {

void ValidateAudioConfig(const AudioConfig& c, const std::string& source) {
  auto bad = [&](const std::string& field, const std::string& expected) {
    return InputError(source, 0, field, "audio: " + expected);
  };
  if (!(c.sample_rate_hz > 0))
    throw bad("sample_rate_hz", "sample_rate_hz and input_rate_hz must be positive");
  if (!(c.input_rate_hz > 0))
    throw bad("input_rate_hz", "sample_rate_hz and input_rate_hz must be positive");
  if (c.input_rate_hz > c.sample_rate_hz)
    throw bad("input_rate_hz", "input_rate_hz must not exceed the device's sample_rate_hz");
  if (c.channels < 1) throw bad("channels", "channels must be >= 1");
  for (const auto* list : {&c.actuator_channels, &c.noise_channels}) {
    const char* field = list == &c.actuator_channels ? "actuator_channels" : "noise_channels";
    for (const int ch : *list)
      if (ch < 0 || ch >= c.channels)
        throw bad(field,
                  fmt::format("channel {} outside 0..{} ({} map)", ch, c.channels - 1, field));
  }
  for (const int a : c.actuator_channels)
    if (std::find(c.noise_channels.begin(), c.noise_channels.end(), a) != c.noise_channels.end())
      throw bad("noise_channels",
                fmt::format("channel {} is both an actuator and a noise channel", a));
  if (!(c.full_scale_mps2 > 0)) throw bad("full_scale_mps2", "full_scale_mps2 must be positive");
  if (!(c.noise_rms_fs >= 0 && c.noise_rms_fs <= 0.5))
    throw bad("noise_rms_fs", "noise_rms_fs must be in 0..0.5");
}

AudioOutput::AudioOutput(const AudioConfig& c, std::unique_ptr<AudioStream> stream)
    : c_(c),
      stream_(std::move(stream)),
      queue_(static_cast<std::size_t>(std::max(64.0, c.queue_s * c.input_rate_hz))),
      noise_rms_(c.noise_rms_fs),
      noise_(c.seed),
      step_(c.input_rate_hz / c.sample_rate_hz) {
  ValidateAudioConfig(c);
  is_actuator_.assign(static_cast<std::size_t>(c.channels), 0);
  is_noise_.assign(static_cast<std::size_t>(c.channels), 0);
  for (const int ch : c.actuator_channels) is_actuator_[static_cast<std::size_t>(ch)] = 1;
  for (const int ch : c.noise_channels) is_noise_[static_cast<std::size_t>(ch)] = 1;
}

AudioOutput::~AudioOutput() {
  if (started_) Stop();
}

void AudioOutput::Start() {
  if (!stream_) throw std::runtime_error("audio: no stream");
  stream_->Start(c_, [this](float* out, unsigned long frames) { Render(out, frames); });
  started_ = true;
}

void AudioOutput::Stop() {
  if (started_ && stream_) stream_->Stop();
  started_ = false;
}

void AudioOutput::Write(double acc) noexcept {
  const float v = std::isfinite(acc) ? static_cast<float>(acc / c_.full_scale_mps2) : 0.f;
  if (!queue_.TryPush(v)) overflows_.fetch_add(1, std::memory_order_relaxed);
}

void AudioOutput::SetSource(devices::SampleSource* source) noexcept {
  source_.store(source, std::memory_order_seq_cst);
  // The callback may still be inside the previous source: wait for it to leave.
  while (in_render_.load(std::memory_order_seq_cst)) {
  }
}

void AudioOutput::Render(float* out, unsigned long frames) noexcept {
  in_render_.store(true, std::memory_order_seq_cst);
  devices::SampleSource* const src = c_.pull ? source_.load(std::memory_order_seq_cst) : nullptr;
  const double rms = noise_rms_.load(std::memory_order_relaxed);
  const auto ch = static_cast<std::size_t>(c_.channels);
  for (unsigned long f = 0; f < frames; ++f) {
    // Linear upsampling from the loop's rate to the device's.
    phase_ += step_;
    while (phase_ >= 1.0) {
      phase_ -= 1.0;
      prev_ = cur_;
      float v;
      if (c_.pull) {
        // The source is the synthesis itself: no sample can be missing (silence before the
        // engine starts and after it stops).
        const double acc = src ? src->NextSample() : 0.0;
        cur_ = std::isfinite(acc) ? acc / c_.full_scale_mps2 : 0.0;
      } else if (queue_.TryPop(&v)) {
        cur_ = v;
      } else {
        cur_ = 0;  // nothing written: silence (the actuator must not hold a stale value)
        underflows_.fetch_add(1, std::memory_order_relaxed);
      }
    }
    double a = prev_ + (cur_ - prev_) * phase_;
    if (a > 1 || a < -1) {
      clipped_.fetch_add(1, std::memory_order_relaxed);
      a = std::clamp(a, -1.0, 1.0);
    }
    for (std::size_t k = 0; k < ch; ++k) {
      double s = 0;
      if (is_actuator_[k])
        s = a;
      else if (is_noise_[k] && rms > 0)
        s = std::clamp(rms * noise_.Normal(), -1.0, 1.0);
      out[f * ch + k] = static_cast<float>(s);
    }
  }
  in_render_.store(false, std::memory_order_seq_cst);
}

// ---------------------------------------------------------------------------------------------
namespace {

std::mutex pa_mutex;
int pa_users = 0;
void PaAcquire() {
  std::lock_guard<std::mutex> lock(pa_mutex);
  if (pa_users++ == 0) {
    // PortAudio probes ALSA and JACK, which print pages of diagnostics on machines without
    // a sound card or a JACK server; hide stderr during the probe (errors still come back
    // through PaError).
    std::fflush(stderr);
    const int saved = dup(2), null = open("/dev/null", O_WRONLY);
    if (saved >= 0 && null >= 0) dup2(null, 2);
    const PaError e = Pa_Initialize();
    if (saved >= 0 && null >= 0) dup2(saved, 2);
    if (saved >= 0) close(saved);
    if (null >= 0) close(null);
    if (e != paNoError) {
      pa_users = 0;
      throw std::runtime_error(std::string("PortAudio: ") + Pa_GetErrorText(e));
    }
  }
}
void PaRelease() {
  std::lock_guard<std::mutex> lock(pa_mutex);
  if (pa_users > 0 && --pa_users == 0) Pa_Terminate();
}

class PortAudioStream final : public AudioStream {
 public:
  PortAudioStream() { PaAcquire(); }
  ~PortAudioStream() override {
    Stop();
    PaRelease();
  }
  void Start(const AudioConfig& c, Render render) override {
    render_ = std::move(render);
    PaStreamParameters p{};
    p.device = Pa_GetDefaultOutputDevice();
    if (!c.device.empty()) {
      p.device = paNoDevice;
      for (PaDeviceIndex i = 0; i < Pa_GetDeviceCount(); ++i) {
        const PaDeviceInfo* d = Pa_GetDeviceInfo(i);
        if (d && d->maxOutputChannels > 0 &&
            std::string(d->name).find(c.device) != std::string::npos)
          p.device = i;
      }
    }
    if (p.device == paNoDevice)
      throw std::runtime_error("PortAudio: no output device" +
                               (c.device.empty() ? std::string() : " matching '" + c.device + "'"));
    p.channelCount = c.channels;
    p.sampleFormat = paFloat32;
    p.suggestedLatency = c.latency_s;
    const PaError e = Pa_OpenStream(&s_, nullptr, &p, c.sample_rate_hz,
                                    paFramesPerBufferUnspecified, paClipOff, &Callback, this);
    if (e != paNoError)
      throw std::runtime_error(std::string("PortAudio: cannot open the stream: ") +
                               Pa_GetErrorText(e));
    const PaError e2 = Pa_StartStream(s_);
    if (e2 != paNoError)
      throw std::runtime_error(std::string("PortAudio: cannot start: ") + Pa_GetErrorText(e2));
    const PaStreamInfo* info = Pa_GetStreamInfo(s_);
    desc_ =
        fmt::format("{} at {:.0f} Hz, output latency {:.1f} ms", Pa_GetDeviceInfo(p.device)->name,
                    c.sample_rate_hz, info ? info->outputLatency * 1e3 : -1.0);
  }
  void Stop() override {
    if (s_) {
      Pa_StopStream(s_);
      Pa_CloseStream(s_);
      s_ = nullptr;
    }
  }
  std::string Describe() const override { return desc_; }

 private:
  static int Callback(const void*, void* out, unsigned long frames, const PaStreamCallbackTimeInfo*,
                      PaStreamCallbackFlags, void* self) {
    static_cast<PortAudioStream*>(self)->render_(static_cast<float*>(out), frames);
    return paContinue;
  }
  PaStream* s_ = nullptr;
  Render render_;
  std::string desc_;
};

}  // namespace

std::unique_ptr<AudioStream> OpenPortAudio() { return std::make_unique<PortAudioStream>(); }

std::vector<std::string> ListAudioDevices() {
  PaAcquire();
  std::vector<std::string> out;
  for (PaDeviceIndex i = 0; i < Pa_GetDeviceCount(); ++i) {
    const PaDeviceInfo* d = Pa_GetDeviceInfo(i);
    if (d && d->maxOutputChannels > 0)
      out.push_back(fmt::format("{}: {} ({} channels, {:.0f} Hz)", i, d->name, d->maxOutputChannels,
                                d->defaultSampleRate));
  }
  PaRelease();
  return out;
}

}  // namespace hapticlab::devices
