#pragma once
/// @file Device interfaces the runner drives: a force-feedback device and a vibrotactile
/// actuator. Back-ends (sim, falcon, audio, ...) implement them; the real-time loops call
/// only the noexcept methods below.

#include <Eigen/Core>
#include <chrono>
#include <cstdint>
#include <string>

#include "hapticlab/core/tool_state.hpp"

namespace hapticlab::devices {

/// What a haptic device can do (from its datasheet or driver).
struct DeviceCapabilities {
  std::string name;                               ///< back-end and model, e.g. "sim", "falcon"
  double max_force_N = 8.0;                       ///< continuous force limit [N]
  double max_stiffness_N_per_m = 3000;            ///< largest stable rendered stiffness [N/m]
  double max_rate_hz = 4000;                      ///< fastest force loop the link supports [Hz]
  Eigen::Vector3d workspace_m{0.16, 0.12, 0.12};  ///< workspace box extents [m]
};

/// What one read of a device gave.
enum class ReadResult : std::uint8_t {
  kOk,         ///< a new sample is in *out
  kNoNewData,  ///< the link worked but carried no new sample (an empty USB frame, a packet
               ///< still in flight); *out is untouched. The engine renders the last sample
               ///< until it is stale.
  kLost,       ///< the exchange failed (USB error, time-out, unplugged); the engine commands
               ///< zero force, and a sustained loss faults the trial
};
const char* ReadResultName(ReadResult r);

/// A force-feedback device. Read and Write are called from the force loop only.
class HapticDevice {
 public:
  virtual ~HapticDevice() = default;
  virtual DeviceCapabilities Capabilities() const = 0;
  /// Reads the newest tool state [device frame]. Never blocks longer than the device's own
  /// transfer.
  virtual ReadResult Read(DeviceSample* out) noexcept = 0;
  /// Commands a force on the tool [N] (already clamped by the renderer).
  virtual void WriteForce(const Eigen::Vector3d& force_N) noexcept = 0;
  /// The loops' time zero: samples are stamped in seconds since it (RtEngine::Start calls this).
  virtual void SetTimeBase(std::chrono::steady_clock::time_point t0) noexcept { (void)t0; }
};

/// Where an actuator that keeps its own clock (a sound card) pulls its input samples from:
/// called on the device's callback thread, once per input sample (SampleRateHz()), so the
/// device's clock paces the synthesis. Real-time: no allocation, no locks, no I/O.
class SampleSource {
 public:
  virtual ~SampleSource() = default;
  virtual double NextSample() noexcept = 0;  ///< acceleration [m/s^2]
};

/// A vibrotactile actuator driven with acceleration samples [m/s^2] at a fixed rate.
class Actuator {
 public:
  virtual ~Actuator() = default;
  virtual double SampleRateHz() const = 0;
  virtual void Write(double acc_mps2) noexcept = 0;
  /// Output samples the device played with no input (an audio underrun); 0 when it cannot tell.
  virtual std::uint64_t Underruns() const noexcept { return 0; }
  /// true: the actuator's own clock pulls samples from SetSource (a sound card); Write is
  /// then not used on the real clock.
  virtual bool PullsSamples() const noexcept { return false; }
  /// Pulling actuators: where samples come from (borrowed; null: silence). Setting null
  /// returns only after the device's callback no longer uses the previous source.
  virtual void SetSource(SampleSource* source) noexcept { (void)source; }
};

/// A participant's rating input (a knob or slider box): polled by the UI thread.
struct RatingEvent {
  bool valid = false;
  double position = 0;   ///< 0..1 along the slider's travel
  bool confirm = false;  ///< the confirm button is down
};
class RatingInput {
 public:
  virtual ~RatingInput() = default;
  /// The newest state, without blocking; valid = false when nothing arrived.
  virtual RatingEvent Poll() = 0;
};

/// Masking noise on the participant's headphones (ch. IV.5.1, V.2.1).
class MaskingNoise {
 public:
  virtual ~MaskingNoise() = default;
  /// Level as RMS in full-scale units (0..1); 0 silences it.
  virtual void SetNoiseLevel(double rms_fs) noexcept = 0;
};

}  // namespace hapticlab::devices
