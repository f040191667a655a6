#include "hapticlab/runner/rt_engine.hpp"

#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <thread>

#include "hapticlab/core/status.hpp"

namespace hapticlab::runner {
namespace {

using Clock = std::chrono::steady_clock;

// Sleeps until an absolute CLOCK_MONOTONIC deadline (std::chrono::steady_clock's clock on
// Linux), retrying on signals. No allocation, no locks.
void SleepUntil(Clock::time_point deadline) noexcept {
  const auto ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(deadline.time_since_epoch()).count();
  const timespec ts{.tv_sec = static_cast<time_t>(ns / 1000000000),
                    .tv_nsec = static_cast<long>(ns % 1000000000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

void AtomicMax(std::atomic<double>& a, double v) noexcept {
  double cur = a.load(std::memory_order_relaxed);
  while (v > cur && !a.compare_exchange_weak(cur, v, std::memory_order_relaxed)) {
  }
}

// Sleeps to `spin` before the deadline, then spins on the clock until it (spin 0: sleeps to
// the deadline). No allocation, no locks.
void WaitUntil(Clock::time_point deadline, Clock::duration spin) noexcept {
  if (spin.count() <= 0) {
    SleepUntil(deadline);
    return;
  }
  if (Clock::now() < deadline - spin) SleepUntil(deadline - spin);
  while (Clock::now() < deadline) {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
  }
}

LoopTiming Summarize(const LatencySummary& late, const LatencySummary& tick, std::uint64_t ticks,
                     std::uint64_t misses) {
  LoopTiming t;
  t.ticks = ticks;
  t.misses = misses;
  t.late_p50_s = late.Quantile(0.5);
  t.late_p99_s = late.Quantile(0.99);
  t.late_p999_s = late.Quantile(0.999);
  t.late_max_s = late.max_s;
  t.tick_p50_s = tick.Quantile(0.5);
  t.tick_p99_s = tick.Quantile(0.99);
  t.tick_p999_s = tick.Quantile(0.999);
  t.tick_max_s = tick.max_s;
  return t;
}

}  // namespace

RtEngine::RtEngine(renderer::HybridRenderer& renderer, devices::HapticDevice& device,
                   devices::Actuator* actuator, const EngineOptions& options,
                   db::TrajectoryStream* force_stream, db::TrajectoryStream* vibration_stream)
    : renderer_(renderer),
      device_(device),
      actuator_(actuator),
      options_(options),
      force_stream_(force_stream),
      vibration_stream_(vibration_stream),
      watchdog_(WatchdogOptions{.stale_after_s = renderer.options().stale_after_s,
                                .max_consecutive_misses = options.max_consecutive_misses,
                                .max_force_N = renderer.options().max_force_N,
                                .max_lost_reads = options.max_lost_reads,
                                .max_lost_s = options.max_lost_s}) {
  HL_REQUIRE(!force_stream_ || force_stream_->channel_count() == ForceStreamChannels().size(),
             "force stream must have the ForceStreamChannels() layout");
  HL_REQUIRE(!vibration_stream_ || vibration_stream_->channel_count() == 1,
             "vibration stream must have one channel");
}

RtEngine::~RtEngine() { Stop(); }

double RtEngine::Now() const {
  if (options_.virtual_clock) return options_.virtual_clock->Now();
  return std::chrono::duration<double>(Clock::now() - t0_).count();
}

DeviceSample RtEngine::LastSample() {
  const Snapshot& s = last_sample_.Read();
  DeviceSample out;
  out.state.p_m = {s.p[0], s.p[1], s.p[2]};
  out.state.v_mps = {s.v[0], s.v[1], s.v[2]};
  out.t_s = s.t;
  return out;
}

void RtEngine::Start() {
  if (running_.exchange(true)) return;
  t0_ = Clock::now();
  device_.SetTimeBase(t0_);
  if (options_.virtual_clock) {
    options_.virtual_clock->Set(0);
    vk_force_ = vk_vibration_ = 0;
    return;
  }
  memory_ = LockMemory(options_.rt.lock_memory);
  underruns_at_start_ = actuator_ ? actuator_->Underruns() : 0;
  threads_configured_.store(0);
  threads_started_ = 1;
  force_thread_ = std::thread([this] { ForceLoop(); });
  pulled_ = renderer_.options().vibration && actuator_ && actuator_->PullsSamples();
  if (pulled_) {
    pulled_source_.k = 0;
    actuator_->SetSource(&pulled_source_);
  } else if (renderer_.options().vibration) {
    ++threads_started_;
    vibration_thread_ = std::thread([this] { VibrationLoop(); });
  }
}

double RtEngine::PulledVibration::NextSample() noexcept {
  const auto t0 = Clock::now();
  const double a = e_.VibrationStep(++k, std::chrono::duration<double>(t0 - e_.t0_).count(), 0.0);
  e_.vibration_tick_.Add(std::chrono::duration<double>(Clock::now() - t0).count());
  return a;
}

void RtEngine::Stop() {
  if (!running_.exchange(false)) return;
  if (force_thread_.joinable()) force_thread_.join();
  if (vibration_thread_.joinable()) vibration_thread_.join();
  if (pulled_) actuator_->SetSource(nullptr);  // returns once the callback has left the engine
  device_.WriteForce(Eigen::Vector3d::Zero());
  if (actuator_) underruns_at_stop_.store(actuator_->Underruns() - underruns_at_start_);
  // Keep the streams' overflow counts: the caller may close the streams after Stop.
  std::uint64_t overflows = 0;
  if (force_stream_) overflows += force_stream_->overflow_count();
  if (vibration_stream_) overflows += vibration_stream_->overflow_count();
  recording_overflows_at_stop_.store(overflows);
}

bool RtEngine::AdvanceTo(double t_s) {
  HL_REQUIRE(options_.virtual_clock != nullptr, "RtEngine::AdvanceTo needs a virtual clock");
  if (!running_.load()) return false;
  const double fr = renderer_.options().force_rate_hz, vr = renderer_.options().vibration_rate_hz;
  const bool vib = renderer_.options().vibration;
  devices::VirtualClock& clock = *options_.virtual_clock;
  while (!device_lost_.load(std::memory_order_relaxed)) {
    // The next force tick, after every vibration tick due before it (a force tick first on a tie).
    const double tf = static_cast<double>(vk_force_ + 1) / fr;
    const double tv = static_cast<double>(vk_vibration_ + 1) / vr;
    if (vib && tv < tf) {
      if (tv > t_s) break;
      clock.Set(tv);
      vibration_late_.Add(0.0);
      VibrationStep(++vk_vibration_, tv, 0.0);
      continue;
    }
    if (tf > t_s) break;
    clock.Set(tf);
    force_late_.Add(0.0);
    ForceStep(++vk_force_, tf, 0.0);
  }
  return !device_lost_.load();
}

void RtEngine::RunFor(std::chrono::duration<double> duration) {
  if (options_.virtual_clock) {
    Start();
    AdvanceTo(duration.count());
    Stop();
    return;
  }
  Start();
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(duration);
  while (Clock::now() < end && !device_lost_.load())
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  Stop();
}

void RtEngine::ForceLoop() {
  force_report_ =
      ConfigureRtThread(options_.rt.priority, options_.rt.cpu, options_.rt.prefault_stack_bytes);
  threads_configured_.fetch_add(1, std::memory_order_release);
  if (options_.on_thread_enter) options_.on_thread_enter();
  const double rate = renderer_.options().force_rate_hz;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate));
  const auto spin = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(std::max(0.0, options_.rt.spin_us) * 1e-6));
  std::uint64_t k = 0;
  while (running_.load(std::memory_order_relaxed)) {
    const auto deadline = t0_ + period * static_cast<std::int64_t>(++k);
    WaitUntil(deadline, spin);
    const auto woke = Clock::now();
    const double late_s = std::chrono::duration<double>(woke - deadline).count();
    force_late_.Add(late_s);
    ForceStep(k, std::chrono::duration<double>(woke - t0_).count(), late_s);
    force_tick_.Add(std::chrono::duration<double>(Clock::now() - woke).count());
  }
  if (options_.on_thread_exit) options_.on_thread_exit();
}

void RtEngine::Record(db::TrajectoryStream* s, double t_s, const float* v) noexcept {
  // On a virtual clock nothing waits on this thread: wait for the writer rather than lose a
  // sample. On the real clock a full queue counts an overflow (the writer fell behind).
  if (options_.virtual_clock)
    while (s->free_slots() == 0) std::this_thread::yield();
  s->Push(t_s, v);
}

void RtEngine::ForceStep(std::uint64_t k, double now_s, double late_s) noexcept {
  const double rate = renderer_.options().force_rate_hz;
  force_jitter_sum_.store(force_jitter_sum_.load(std::memory_order_relaxed) + late_s,
                          std::memory_order_relaxed);
  AtomicMax(force_jitter_max_, late_s);
  if (late_s > 1.0 / rate) force_misses_.fetch_add(1, std::memory_order_relaxed);
  DeviceSample fresh;
  renderer::ForceCommand cmd;
  const devices::ReadResult rr = device_.Read(&fresh);
  if (rr == devices::ReadResult::kOk) {
    // Device frame -> sample frame (the renderer's surface: base plane z = 0, +z out of it).
    const Eigen::Isometry3d& T = options_.sample_from_device;
    last_good_.state.p_m = T * fresh.state.p_m;
    last_good_.state.v_mps = T.linear() * fresh.state.v_mps;
    last_good_.t_s = fresh.t_s;
    have_good_ = true;
    auto& snap = last_sample_.WriteSlot();
    for (int i = 0; i < 3; ++i)
      snap.p[i] = last_good_.state.p_m[i], snap.v[i] = last_good_.state.v_mps[i];
    snap.t = last_good_.t_s;
    last_sample_.Publish();
  } else if (rr == devices::ReadResult::kNoNewData) {
    empty_reads_.fetch_add(1, std::memory_order_relaxed);
  }
  // No new data: the newest good sample again (the stale check bounds how long).
  const DeviceSample& sample = last_good_;
  const bool render = rr != devices::ReadResult::kLost && have_good_;
  if (render) cmd = renderer_.ForceTick(sample, now_s);
  if (render && cmd.raw.in_contact) contact_ticks_.fetch_add(1, std::memory_order_relaxed);
  // The watchdog has the last word: zero force on any fault or lost read, this very tick.
  const Eigen::Vector3d command = watchdog_.Check(rr, sample, now_s, late_s, 1.0 / rate,
                                                  render ? cmd.force_N : Eigen::Vector3d::Zero(),
                                                  render && cmd.vibration_fault);
  const bool fault = watchdog_.last() != FaultKind::kNone || cmd.fault || !render;
  if (watchdog_.last() == FaultKind::kDisconnect) {
    disconnects_.fetch_add(1, std::memory_order_relaxed);
    device_lost_.store(true);
  } else if (watchdog_.last() == FaultKind::kDeadlineMiss) {
    miss_faults_.fetch_add(1, std::memory_order_relaxed);
  }
  // Sample frame -> device frame.
  device_.WriteForce(options_.sample_from_device.linear().transpose() * command);
  force_ticks_.fetch_add(1, std::memory_order_relaxed);
  force_last_s_.store(now_s, std::memory_order_relaxed);
  if (force_stream_) {
    const auto& s = sample.state;
    using db::Col;
    using db::ForceChannel;
    float v[db::kForceChannelCount];
    v[Col(ForceChannel::kX_m)] = static_cast<float>(s.p_m.x());
    v[Col(ForceChannel::kY_m)] = static_cast<float>(s.p_m.y());
    v[Col(ForceChannel::kZ_m)] = static_cast<float>(s.p_m.z());
    v[Col(ForceChannel::kVx_mps)] = static_cast<float>(s.v_mps.x());
    v[Col(ForceChannel::kVy_mps)] = static_cast<float>(s.v_mps.y());
    v[Col(ForceChannel::kVz_mps)] = static_cast<float>(s.v_mps.z());
    v[Col(ForceChannel::kFx_N)] = static_cast<float>(cmd.raw.force_N.x());
    v[Col(ForceChannel::kFy_N)] = static_cast<float>(cmd.raw.force_N.y());
    v[Col(ForceChannel::kFz_N)] = static_cast<float>(cmd.raw.force_N.z());
    v[Col(ForceChannel::kCmdFx_N)] = static_cast<float>(command.x());
    v[Col(ForceChannel::kCmdFy_N)] = static_cast<float>(command.y());
    v[Col(ForceChannel::kCmdFz_N)] = static_cast<float>(command.z());
    v[Col(ForceChannel::kNormal_N)] = static_cast<float>(cmd.raw.normal_force_N);
    v[Col(ForceChannel::kSpeed_mps)] = static_cast<float>(cmd.raw.tangential_speed_mps);
    v[Col(ForceChannel::kFault)] = fault ? 1.f : 0.f;
    v[Col(ForceChannel::kLate_s)] = static_cast<float>(late_s);
    Record(force_stream_, static_cast<double>(k) / rate, v);
  }
}

void RtEngine::VibrationLoop() {
  // One priority below the force loop, on the next CPU; no spin (at 10 kHz a spin of 20 us
  // would spend a fifth of a core, and the audio buffer absorbs the vibration loop's lateness).
  const int prio = options_.rt.priority > 1 ? options_.rt.priority - 1 : options_.rt.priority;
  const int cpu = options_.rt.cpu >= 0 ? options_.rt.cpu + 1 : -1;
  vibration_report_ = ConfigureRtThread(prio, cpu, options_.rt.prefault_stack_bytes);
  threads_configured_.fetch_add(1, std::memory_order_release);
  if (options_.on_thread_enter) options_.on_thread_enter();
  const double rate = renderer_.options().vibration_rate_hz;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate));
  std::uint64_t k = 0;
  while (running_.load(std::memory_order_relaxed)) {
    const auto deadline = t0_ + period * static_cast<std::int64_t>(++k);
    SleepUntil(deadline);
    const auto woke = Clock::now();
    const double late_s = std::chrono::duration<double>(woke - deadline).count();
    vibration_late_.Add(late_s);
    VibrationStep(k, std::chrono::duration<double>(woke - t0_).count(), late_s);
    vibration_tick_.Add(std::chrono::duration<double>(Clock::now() - woke).count());
  }
  if (options_.on_thread_exit) options_.on_thread_exit();
}

double RtEngine::VibrationStep(std::uint64_t k, double now_s, double late_s) noexcept {
  const double rate = renderer_.options().vibration_rate_hz;
  AtomicMax(vibration_jitter_max_, late_s);
  if (late_s > 1.0 / rate) vibration_misses_.fetch_add(1, std::memory_order_relaxed);
  const double a = renderer_.VibrationTick();
  if (actuator_ && !pulled_) actuator_->Write(a);
  vibration_ticks_.fetch_add(1, std::memory_order_relaxed);
  vibration_last_s_.store(now_s, std::memory_order_relaxed);
  if (vibration_stream_) {
    const float v = static_cast<float>(a);
    Record(vibration_stream_, static_cast<double>(k) / rate, &v);
  }
  return a;
}

EngineStats RtEngine::Stats() const {
  EngineStats s;
  s.force_ticks = force_ticks_.load();
  s.contact_ticks = contact_ticks_.load();
  s.empty_reads = empty_reads_.load();
  s.lost_reads = watchdog_.lost_reads();
  s.vibration_ticks = vibration_ticks_.load();
  s.force_deadline_misses = force_misses_.load();
  s.vibration_deadline_misses = vibration_misses_.load();
  s.disconnects = disconnects_.load();
  s.miss_faults = miss_faults_.load();
  s.nan_faults = watchdog_.count(FaultKind::kNaN);
  s.stale_faults = watchdog_.count(FaultKind::kStale);
  s.bad_commands = watchdog_.count(FaultKind::kBadCommand);
  s.vibration_faults = watchdog_.count(FaultKind::kVibrationModel);
  s.force_jitter_max_s = force_jitter_max_.load();
  s.force_jitter_mean_s =
      s.force_ticks ? force_jitter_sum_.load() / static_cast<double>(s.force_ticks) : 0;
  s.vibration_jitter_max_s = vibration_jitter_max_.load();
  const double tf = force_last_s_.load(), tv = vibration_last_s_.load();
  s.achieved_force_rate_hz = tf > 0 ? static_cast<double>(s.force_ticks) / tf : 0;
  s.achieved_vibration_rate_hz = tv > 0 ? static_cast<double>(s.vibration_ticks) / tv : 0;
  if (running_.load()) {
    if (force_stream_) s.recording_overflows += force_stream_->overflow_count();
    if (vibration_stream_) s.recording_overflows += vibration_stream_->overflow_count();
  } else {
    s.recording_overflows = recording_overflows_at_stop_.load();
  }
  s.virtual_clock = options_.virtual_clock != nullptr;
  s.memory = memory_;
  if (!s.virtual_clock && threads_configured_.load(std::memory_order_acquire) == threads_started_) {
    s.force_thread = force_report_;
    s.vibration_thread = vibration_report_;
    s.priority_status = "force: " + force_report_.priority_status;
    if (threads_started_ > 1)
      s.priority_status += "; vibration: " + vibration_report_.priority_status;
    if (pulled_) s.priority_status += "; vibration: paced by the actuator's callback";
  } else {
    s.priority_status = priority_status_;
  }
  s.audio_underruns = running_.load()
                          ? (actuator_ ? actuator_->Underruns() - underruns_at_start_ : 0)
                          : underruns_at_stop_.load();
  const EngineTiming t = Timing();
  s.force_timing = Summarize(t.force_late, t.force_tick, s.force_ticks, s.force_deadline_misses);
  s.vibration_timing =
      Summarize(t.vibration_late, t.vibration_tick, s.vibration_ticks, s.vibration_deadline_misses);
  return s;
}

EngineTiming RtEngine::Timing() const {
  return {force_late_.Snapshot(), force_tick_.Snapshot(), vibration_late_.Snapshot(),
          vibration_tick_.Snapshot()};
}

}  // namespace hapticlab::runner
