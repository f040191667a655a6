// The audio back-end through a fake stream: channel map, upsampling, masking noise level,
// underflow and clipping counters, configuration errors.

#include "hapticlab/devices/audio.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::devices::audio_test {
namespace {

class FakeStream : public AudioStream {
 public:
  void Start(const AudioConfig&, Render r) override { render = std::move(r); }
  void Stop() override { render = nullptr; }
  std::string Describe() const override { return "fake"; }
  Render render;
};

TEST(Audio, ActuatorChannelCarriesTheSignalAndHeadphonesTheNoise) {
  AudioConfig c;
  c.sample_rate_hz = 40000;
  c.input_rate_hz = 10000;
  c.channels = 3;
  c.actuator_channels = {0};
  c.noise_channels = {1, 2};
  c.full_scale_mps2 = 20;
  c.noise_rms_fs = 0.1;
  c.pull = false;  // the queue path (the pull path: PullModeSynthesisIsPacedByTheCallback)
  auto stream = std::make_unique<FakeStream>();
  FakeStream* s = stream.get();
  AudioOutput out(c, std::move(stream));
  out.Start();
  ASSERT_TRUE(s->render);
  // 0.2 s of a 250 Hz sine of amplitude 10 m/s^2 from the vibration loop (10 kHz).
  const int n_in = 2000;
  std::vector<float> buf(static_cast<std::size_t>(n_in * 4 * 3));
  {
    // The vibration loop and the callback take turns, 10 ms at a time, as they would run.
    test::NoAllocGuard guard;
    for (int chunk = 0; chunk < n_in / 100; ++chunk) {
      for (int k = chunk * 100; k < chunk * 100 + 100; ++k)
        out.Write(10 * std::sin(2 * std::numbers::pi * 250 * k / 10000.0));
      s->render(buf.data() + static_cast<std::ptrdiff_t>(chunk) * 400 * 3,
                chunk + 1 < n_in / 100 ? 400 : 392);
    }
    EXPECT_EQ(guard.count(), 0u) << "Write and the callback allocate nothing";
  }
  double peak = 0, n1 = 0, n2 = 0, cross = 0;
  for (int f = 40; f < n_in * 4 - 8; ++f) {
    const float a = buf[static_cast<std::size_t>(3 * f)];
    peak = std::max(peak, static_cast<double>(std::abs(a)));
    n1 += buf[static_cast<std::size_t>(3 * f + 1)] * buf[static_cast<std::size_t>(3 * f + 1)];
    n2 += buf[static_cast<std::size_t>(3 * f + 2)] * buf[static_cast<std::size_t>(3 * f + 2)];
    cross += buf[static_cast<std::size_t>(3 * f + 1)] * a;
  }
  const double frames = n_in * 4 - 48;
  EXPECT_NEAR(peak, 0.5, 0.01) << "10 m/s^2 at 20 m/s^2 full scale";
  EXPECT_NEAR(std::sqrt(n1 / frames), 0.1, 0.005);
  EXPECT_NEAR(std::sqrt(n2 / frames), 0.1, 0.005);
  EXPECT_LT(std::abs(cross / frames), 0.003) << "noise is independent of the signal";
  EXPECT_EQ(out.underflows(), 0u);
  // Noise off: silence on the headphones.
  out.SetNoiseLevel(0);
  for (int k = 0; k < 100; ++k) out.Write(0);
  s->render(buf.data(), 400);
  for (int f = 0; f < 400; ++f) EXPECT_EQ(buf[static_cast<std::size_t>(3 * f + 1)], 0.f);
}

TEST(Audio, UnderflowsAndClippingAreCountedNeverHeld) {
  AudioConfig c;
  c.sample_rate_hz = 10000;
  c.input_rate_hz = 10000;
  c.noise_channels = {};
  c.channels = 1;
  c.full_scale_mps2 = 1;
  c.pull = false;
  auto stream = std::make_unique<FakeStream>();
  FakeStream* s = stream.get();
  AudioOutput out(c, std::move(stream));
  out.Start();
  out.Write(3.0);  // beyond full scale
  out.Write(0.5);
  std::vector<float> buf(10);
  s->render(buf.data(), 10);
  EXPECT_EQ(out.clipped(), 1u);
  EXPECT_FLOAT_EQ(buf[0], 0.f);  // one input sample of interpolation latency
  EXPECT_FLOAT_EQ(buf[1], 1.f);
  EXPECT_FLOAT_EQ(buf[2], 0.5f);
  EXPECT_EQ(out.underflows(), 8u);  // frames 2-9 each needed a new input sample
  for (int k = 3; k < 10; ++k)
    EXPECT_EQ(buf[static_cast<std::size_t>(k)], 0.f)
        << "an empty queue is silence, not the last value";
  // A full queue drops (and counts) instead of waiting.
  for (int k = 0; k < 10000; ++k) out.Write(0.1);
  EXPECT_GT(out.overflows(), 0u);
}

// A source that counts its calls and returns a ramp.
class Ramp : public SampleSource {
 public:
  double NextSample() noexcept override { return 0.01 * static_cast<double>(calls++); }
  std::uint64_t calls = 0;
};

TEST(Audio, PullModeSynthesisIsPacedByTheCallback) {
  AudioConfig c;
  c.sample_rate_hz = 40000;
  c.input_rate_hz = 10000;
  c.channels = 1;
  c.noise_channels = {};
  c.full_scale_mps2 = 100;
  auto stream = std::make_unique<FakeStream>();
  FakeStream* s = stream.get();
  AudioOutput out(c, std::move(stream));
  ASSERT_TRUE(out.PullsSamples());
  out.Start();
  std::vector<float> buf(4000);
  s->render(buf.data(), 400);  // no source yet: silence, not an underflow
  for (int f = 0; f < 400; ++f) ASSERT_EQ(buf[static_cast<std::size_t>(f)], 0.f);
  Ramp ramp;
  out.SetSource(&ramp);
  {
    test::NoAllocGuard guard;
    s->render(buf.data(), 4000);
    EXPECT_EQ(guard.count(), 0u);
  }
  // The callback asked for exactly one input sample per 4 output frames: the sound card's
  // clock sets the synthesis rate.
  EXPECT_EQ(ramp.calls, 1000u);
  EXPECT_EQ(out.underflows(), 0u);
  // The ramp (0.01 m/s^2 per input sample), linearly upsampled with one input sample of
  // latency: after frame f the callback has pulled n = (f + 1) / 4 samples (fractional) and
  // plays sample n - 2 (0-based), i.e. 0.01 (n - 2) m/s^2, at full scale 100 m/s^2.
  for (int f = 8; f < 4000; ++f)
    ASSERT_NEAR(buf[static_cast<std::size_t>(f)], 0.01 * ((f + 1) / 4.0 - 2.0) / 100.0, 1e-7) << f;
  out.SetSource(nullptr);
  s->render(buf.data(), 8);
  EXPECT_EQ(ramp.calls, 1000u) << "no call after the source was removed";
}

TEST(Audio, BadConfigurationsNameTheField) {
  AudioConfig c;
  c.actuator_channels = {2};
  EXPECT_THROW(ValidateAudioConfig(c), InputError);
  c = {};
  c.noise_channels = {0};  // the actuator's channel
  try {
    ValidateAudioConfig(c);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.diagnostics().at(0).field, "noise_channels");
    EXPECT_NE(std::string(e.what()).find("both an actuator and a noise channel"),
              std::string::npos);
  }
  c = {};
  c.input_rate_hz = 96000;
  EXPECT_THROW(ValidateAudioConfig(c), InputError);
}

}  // namespace
}  // namespace hapticlab::devices::audio_test
