#pragma once
/// @file The real-time engine: a force loop and a vibration loop on their own threads,
/// each waking at absolute deadlines, sharing state only through the renderer's lock-free
/// hand-off, and recording through the db writer's SPSC streams.
///
/// Two clocks, one tick code: on the real clock each loop has its own thread and sleeps to
/// absolute deadlines; on a virtual clock (EngineOptions::virtual_clock) the caller's thread
/// steps the same ForceStep/VibrationStep in time order (every force tick, then the
/// vibration ticks up to the next one) as fast as they run, setting the clock before each
/// tick, so simulated devices see the time they would see on a rig. A virtual run is
/// deterministic and never drops a recorded sample (it waits for the writer instead).
///
/// Frames: the device reports in its own frame; the engine maps positions and velocities into
/// the sample's frame (EngineOptions::sample_from_device, from the rig file) before the
/// renderer and maps the renderer's force back into the device frame. The force stream is
/// recorded in the sample frame.
///
/// Device reads: kOk renders the new sample; kNoNewData renders the newest good sample again
/// (until it is stale); kLost commands zero force on that tick, and a sustained loss is a
/// disconnect.
///
/// Vibration clocked by the output device: on the real clock, an actuator that keeps its own
/// clock (Actuator::PullsSamples: the sound card) gets the vibration synthesis as its
/// SampleSource and its callback runs the vibration ticks; no vibration thread is started and
/// no queue between a thread and the callback can underrun. The virtual clock steps the
/// vibration ticks itself as before (deterministic).
///
/// Safety: the Watchdog (watchdog.hpp) checks every force tick: a sustained loss of the link
/// (disconnect), NaN or stale data, `max_consecutive_misses` late ticks in a row, or a bad
/// command give zero force on that tick, latch the trial as faulted and queue an event; the
/// renderer itself also zeroes NaN and stale data and clamps to the device limit.

#include <Eigen/Geometry>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>

#include "hapticlab/core/latency_histogram.hpp"
#include "hapticlab/core/triple_buffer.hpp"
#include "hapticlab/db/force_record.hpp"
#include "hapticlab/db/trajectory_writer.hpp"
#include "hapticlab/devices/clock.hpp"
#include "hapticlab/devices/device.hpp"
#include "hapticlab/renderer/hybrid.hpp"
#include "hapticlab/runner/rt_thread.hpp"
#include "hapticlab/runner/watchdog.hpp"

namespace hapticlab::runner {

/// Channels of the force stream, in order: db::ForceChannel (db/force_record.hpp names each
/// column, its unit, frame and meaning).
inline const std::vector<std::string>& ForceStreamChannels() { return db::ForceChannelNames(); }
/// Channels of the vibration stream.
inline const std::vector<std::string>& VibrationStreamChannels() {
  static const std::vector<std::string> kChannels{std::string(db::kVibrationChannel.name)};
  return kChannels;
}

struct EngineOptions {
  int max_consecutive_misses = 3;  ///< late force ticks in a row before forcing zero force
  int max_lost_reads = 10;         ///< lost reads in a row that fault the trial (disconnect)
  double max_lost_s = 0.010;       ///< time without a good read that faults the trial [s]
  /// What the loop threads ask for before their first tick (real clock only): timer slack
  /// 1 ns always; spin, SCHED_FIFO priority (the vibration loop one below the force loop),
  /// memory locking, CPU pinning (the vibration loop on the next CPU) as asked. Outcomes in
  /// EngineStats; nothing is fatal.
  RtThreadOptions rt;
  /// Test hooks run on each loop thread before its first and after its last tick (real
  /// clock only).
  std::function<void()> on_thread_enter, on_thread_exit;
  /// Borrowed; when set the engine runs on it (see the file comment) instead of the real clock.
  devices::VirtualClock* virtual_clock = nullptr;
  /// Pose of the device frame in the sample frame: p_sample = sample_from_device * p_device.
  Eigen::Isometry3d sample_from_device = Eigen::Isometry3d::Identity();
};

/// One loop's timing over a run [s]: wake-up lateness (how long after its deadline a tick
/// started) and tick duration (from waking to the end of the tick), as percentiles of the
/// loop's histogram. On a virtual clock lateness is 0 and durations are not measured.
struct LoopTiming {
  std::uint64_t ticks = 0, misses = 0;
  double late_p50_s = 0, late_p99_s = 0, late_p999_s = 0, late_max_s = 0;
  double tick_p50_s = 0, tick_p99_s = 0, tick_p999_s = 0, tick_max_s = 0;
};
/// The loops' histograms (for storage and merging across trials).
struct EngineTiming {
  LatencySummary force_late, force_tick, vibration_late, vibration_tick;
};

/// Counters and timing statistics, written by the loops, read by anyone.
struct EngineStats {
  std::uint64_t force_ticks = 0, vibration_ticks = 0;
  std::uint64_t force_deadline_misses = 0, vibration_deadline_misses = 0;
  std::uint64_t disconnects = 0, miss_faults = 0, nan_faults = 0, stale_faults = 0,
                bad_commands = 0;
  /// Runaway vibration models muted by the renderer (FaultKind::kVibrationModel).
  std::uint64_t vibration_faults = 0;
  std::uint64_t recording_overflows = 0;
  std::uint64_t contact_ticks = 0;  ///< force ticks with the stylus inside the model's surface
  std::uint64_t empty_reads = 0, lost_reads = 0;  ///< reads with no new data, lost reads
  double force_jitter_max_s = 0, force_jitter_mean_s = 0;
  double vibration_jitter_max_s = 0;
  double achieved_force_rate_hz = 0, achieved_vibration_rate_hz = 0;
  std::string priority_status;  ///< what became of the real-time priority request (both loops)
  LoopTiming force_timing, vibration_timing;
  RtThreadReport force_thread, vibration_thread;  ///< what each loop thread got (real clock)
  MemoryLockReport memory;
  std::uint64_t audio_underruns = 0;  ///< actuator output samples with no input during the run
  bool virtual_clock = false;
};

class RtEngine {
 public:
  /// The engine borrows everything; all must outlive it (streams at least until Stop).
  /// `actuator`, `force_stream` and `vibration_stream` may be null; a stream that is given
  /// has the layout of ForceStreamChannels() / VibrationStreamChannels() (PreconditionError
  /// otherwise).
  RtEngine(renderer::HybridRenderer& renderer, devices::HapticDevice& device,
           devices::Actuator* actuator, const EngineOptions& options = {},
           db::TrajectoryStream* force_stream = nullptr,
           db::TrajectoryStream* vibration_stream = nullptr);
  ~RtEngine();
  RtEngine(const RtEngine&) = delete;
  RtEngine& operator=(const RtEngine&) = delete;

  /// Starts both loops. Time zero of the loops (and of device samples) is this call.
  void Start();
  /// Stops both loops, commands zero force, joins.
  void Stop();
  /// Runs for `duration` (or until the device reports a disconnect), then stops.
  void RunFor(std::chrono::duration<double> duration);
  /// Virtual clock only, between Start and Stop: runs every tick due up to `t_s` (seconds
  /// since Start). Returns false once the device reported a disconnect.
  bool AdvanceTo(double t_s);
  bool is_virtual() const { return options_.virtual_clock != nullptr; }
  EngineStats Stats() const;
  /// The loops' histograms (copies; any thread).
  EngineTiming Timing() const;
  /// The force loop's watchdog: tripped() tells whether the trial faulted; PopEvent drains its
  /// events (call from a non-real-time thread).
  Watchdog& watchdog() { return watchdog_; }
  /// The newest device sample the force loop read, in the sample frame (for screens; one
  /// reader thread).
  DeviceSample LastSample();
  /// Seconds since Start on the loops' clock (virtual or real).
  double Now() const;

 private:
  void ForceLoop();
  void VibrationLoop();
  // One tick of each loop (the same code on either clock). k: 1-based tick number.
  void ForceStep(std::uint64_t k, double now_s, double late_s) noexcept;
  // Returns the acceleration it synthesized (also written to a pushing actuator).
  double VibrationStep(std::uint64_t k, double now_s, double late_s) noexcept;
  // The vibration synthesis as the pulling actuator's source (its callback thread runs it).
  class PulledVibration final : public devices::SampleSource {
   public:
    explicit PulledVibration(RtEngine& e) : e_(e) {}
    double NextSample() noexcept override;
    std::uint64_t k = 0;

   private:
    RtEngine& e_;
  };
  PulledVibration pulled_source_{*this};
  bool pulled_ = false;  // real clock: the actuator's callback runs the vibration synthesis
  void Record(db::TrajectoryStream* s, double t_s, const float* v) noexcept;

  renderer::HybridRenderer& renderer_;
  devices::HapticDevice& device_;
  devices::Actuator* actuator_;
  EngineOptions options_;
  db::TrajectoryStream* force_stream_;
  db::TrajectoryStream* vibration_stream_;
  std::chrono::steady_clock::time_point t0_;
  std::atomic<bool> running_{false};
  std::atomic<bool> device_lost_{false};
  std::thread force_thread_, vibration_thread_;
  // Statistics (single writer each).
  std::atomic<std::uint64_t> force_ticks_{0}, vibration_ticks_{0};
  std::atomic<std::uint64_t> force_misses_{0}, vibration_misses_{0}, disconnects_{0},
      miss_faults_{0};
  std::atomic<double> force_jitter_max_{0}, force_jitter_sum_{0}, vibration_jitter_max_{0};
  std::atomic<double> force_last_s_{0}, vibration_last_s_{0};
  std::atomic<std::uint64_t> recording_overflows_at_stop_{0};
  std::atomic<std::uint64_t> contact_ticks_{0}, empty_reads_{0};
  DeviceSample last_good_;  // force loop only: the newest good sample (sample frame)
  bool have_good_ = false;
  std::string priority_status_ = "not requested";
  LatencyHistogram force_late_, force_tick_, vibration_late_, vibration_tick_;
  // Written by each loop thread before its first tick, read after Stop (joined).
  RtThreadReport force_report_, vibration_report_;
  MemoryLockReport memory_;
  std::uint64_t underruns_at_start_ = 0;
  std::atomic<std::uint64_t> underruns_at_stop_{0};
  std::atomic<int> threads_configured_{0};  // release: the loop's report is written
  int threads_started_ = 0;
  Watchdog watchdog_;
  std::uint64_t vk_force_ = 0, vk_vibration_ = 0;  // virtual clock: ticks done
  struct Snapshot {
    double p[3], v[3], t;
  };
  TripleBuffer<Snapshot> last_sample_;
};

}  // namespace hapticlab::runner
