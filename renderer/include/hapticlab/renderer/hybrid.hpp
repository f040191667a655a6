#pragma once
/// @file The hybrid renderer's two ticks (dissertation ch. V.1.4): the force tick computes
/// the texture force, low-passes it at f_c, clamps it and publishes the vibration filter;
/// the vibration tick synthesizes acceleration and high-passes it at f_c. The ticks may run
/// on two threads (one each); they share only a lock-free triple buffer.
///
/// Safety (every tick): non-finite device data, data older than `stale_after_s`, or a
/// non-finite result command zero force on that very tick, reset the filters and count a
/// fault; the commanded force's magnitude never exceeds `max_force_N`. A vibration model that
/// runs away (a non-finite sample, or a neural model beyond its declared maximum level,
/// kNeuralMaxLevel) is muted by the vibration tick for the rest of the renderer's life, and the
/// next force tick is a fault (zero force, `vibration_faults`, ForceCommand::vibration_fault):
/// the vibration thread only sets an atomic flag, nothing is allocated or locked.

#include <atomic>
#include <cstdint>
#include <memory>

#include "hapticlab/core/triple_buffer.hpp"
#include "hapticlab/renderer/biquad.hpp"
#include "hapticlab/renderer/force.hpp"
#include "hapticlab/renderer/neural.hpp"
#include "hapticlab/renderer/upsampler.hpp"
#include "hapticlab/renderer/vibration.hpp"

namespace hapticlab::renderer {

/// How one trial renders a material (a protocol's "method").
struct RenderOptions {
  ForceAlgorithm algorithm = ForceAlgorithm::kFric2;
  bool vibration = true;                       ///< synthesize vibration at all
  bool hybrid_filter = true;                   ///< low-pass force and high-pass vibration at f_c
  double force_rate_hz = 1000;                 ///< force tick rate [Hz]
  double vibration_rate_hz = 10000;            ///< vibration tick rate [Hz]
  double max_force_N = 8.0;                    ///< device force limit [N]
  double device_max_stiffness_N_per_m = 3000;  ///< base K defaults to half of this (ch. V)
  double stale_after_s = 0.005;                ///< device data older than this is a fault [s]
  std::uint64_t seed = 1;                      ///< vibration noise seed (recorded with the trial)
};

/// Device reading handed to the force tick (core/tool_state.hpp, shared with devices/).
using hapticlab::DeviceSample;

/// What the force tick commands and observes.
struct ForceCommand {
  Eigen::Vector3d force_N = Eigen::Vector3d::Zero();  ///< commanded (filtered, clamped) [N]
  ForceOutput raw;                                    ///< unfiltered model output
  bool fault = false;                                 ///< this tick was a fault: force is zero
  bool vibration_fault = false;                       ///< the vibration model's fault (runaway)
  bool saturated = false;                             ///< the limit clamped this tick
};

/// Fault and activity counters (single writer per field: force or vibration thread).
struct RtCounters {
  std::atomic<std::uint64_t> force_ticks{0};
  std::atomic<std::uint64_t> vibration_ticks{0};
  std::atomic<std::uint64_t> nan_faults{0};
  std::atomic<std::uint64_t> stale_faults{0};
  std::atomic<std::uint64_t> saturations{0};
  std::atomic<std::uint64_t> vibration_faults{0};  ///< vibration models muted for running away
};

class HybridRenderer {
 public:
  /// @throws PreconditionError on non-positive loop rates or force limit; InputError (naming
  /// the material's file) when the material does not fit the loops (its cut-off above a
  /// loop's Nyquist rate, a vibration model sampled faster than the vibration loop).
  HybridRenderer(const MaterialModel& m, const RenderOptions& o);

  /// Force thread: one tick at `now_s`. noexcept, allocation-free.
  ForceCommand ForceTick(const DeviceSample& in, double now_s) noexcept;
  /// Vibration thread: the next actuator sample [m/s^2]. noexcept, allocation-free.
  double VibrationTick() noexcept;

  const RtCounters& counters() const { return counters_; }
  /// The vibration model ran away and is muted (vibration thread's view).
  bool vibration_muted() const { return vib_muted_.load(std::memory_order_acquire); }
  const RenderOptions& options() const { return options_; }
  double cutoff_hz() const { return cutoff_hz_; }
  /// Taps per phase of the band-limited upsampler (model rate -> vibration rate).
  static constexpr int kUpsampleTapsPerPhase = 32;
  /// The upsampling factor when the rates' ratio is an integer, else 0 (linear interpolation).
  int upsample_factor() const { return upsample_ ? up_.factor() : 0; }

 private:
  void Fault(std::atomic<std::uint64_t>& counter) noexcept;
  double ModelSample(const ArFilter& f) noexcept;  // the next model-rate sample, guarded

  RenderOptions options_;
  double cutoff_hz_;
  bool filter_on_ = false;  // hybrid_filter and f_c > 0
  ForceModel force_;
  std::array<Biquad, 3> force_lp_;
  VibrationInterpolator interp_;
  TripleBuffer<ArFilter> filter_box_;
  // vibration-thread state
  ArSynth synth_;
  std::unique_ptr<NeuralSynth> neural_;  // the material's neural model, when it has one
  Biquad vib_hp_;
  double phase_ = 1.0;  // fraction of a model-rate period elapsed (linear interpolation)
  double step_ = 0.2;   // model rate / vibration rate
  double prev_ = 0, next_ = 0;
  bool upsample_ = false;  // integer rate ratio: band-limited polyphase upsampling
  PolyphaseUpsampler up_;
  int up_phase_ = 0;
  std::atomic<bool> vib_muted_{false};          // set by the vibration thread, never cleared
  std::atomic<bool> vib_fault_pending_{false};  // vibration thread -> the next force tick
  RtCounters counters_;
};

}  // namespace hapticlab::renderer
