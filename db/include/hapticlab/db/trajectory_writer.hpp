#pragma once
/// @file Background writer of trajectory streams: real-time threads push samples into
/// lock-free queues; one writer thread packs them into chunks and commits them to SQLite.

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "hapticlab/core/spsc_queue.hpp"
#include "hapticlab/core/triple_buffer.hpp"
#include "hapticlab/db/database.hpp"

namespace hapticlab::db {

/// Most channels one stream may carry (position, velocity, force, commanded force, ...).
inline constexpr std::size_t kMaxChannels = 16;

/// One sample as queued between the real-time thread and the writer.
struct TrajectorySample {
  double t_s;                              ///< sample time [s]
  std::array<float, kMaxChannels> values;  ///< first `channels` entries are used
};

/// Options of a TrajectoryWriter.
struct WriterOptions {
  std::size_t queue_capacity = 1 << 16;  ///< samples per stream queue (16 s at 4 kHz)
  std::size_t chunk_samples = 2048;      ///< samples per stored chunk
  bool start_thread = true;              ///< false: call Start() later (tests)
  /// Chunks whose commit failed are kept and retried on the next pass, up to this many
  /// float32 values in all (64 MiB); beyond it the oldest are dropped and counted as lost.
  std::size_t retry_limit_values = std::size_t{16} << 20;
  int busy_timeout_ms = 10000;  ///< wait for another writer this long per commit
};

/// A stream's producer end. Push is wait-free, allocation-free and never throws; it is the
/// only call a real-time thread makes.
class TrajectoryStream {
 public:
  /// Queues one sample of `channel_count()` values. Returns false (and counts an overflow)
  /// when the queue is full; never waits.
  bool Push(double t_s, const float* values) noexcept {
    offered_.fetch_add(1, std::memory_order_relaxed);
    TrajectorySample s{};
    s.t_s = t_s;
    for (std::size_t i = 0; i < channels_; ++i) s.values[i] = values[i];
    return queue_.TryPush(s);
  }
  std::size_t channel_count() const { return channels_; }
  /// Room left in the queue (approximate while the writer drains it). A producer without a
  /// deadline (the engine on a virtual clock) waits for room instead of losing samples.
  std::size_t free_slots() const noexcept { return queue_.capacity() - queue_.size(); }
  std::uint64_t overflow_count() const { return queue_.overflow_count(); }
  std::uint64_t written_count() const { return written_.load(std::memory_order_relaxed); }
  std::uint64_t offered_count() const { return offered_.load(std::memory_order_relaxed); }
  /// The trial attempt this stream's chunks are tagged with.
  int attempt() const { return attempt_; }
  /// The newest sample the writer thread has taken from the queue (what was recorded, as it
  /// will be stored), for a live display; false before the first. One reader thread (the
  /// session's), never the producer: the producer's Push is untouched by it.
  bool Latest(TrajectorySample* out) noexcept {
    const TrajectorySample& s = latest_.Read();
    if (!(s.t_s >= 0)) return false;
    *out = s;
    return true;
  }

 private:
  friend class TrajectoryWriter;
  TrajectoryStream(std::int64_t trial_id, int attempt, std::string name, double rate_hz,
                   std::vector<std::string> channels, std::size_t capacity);

  std::int64_t trial_id_;
  int attempt_;
  std::string name_;
  double rate_hz_;
  std::vector<std::string> channel_names_;
  std::size_t channels_;
  SpscQueue<TrajectorySample> queue_;
  std::atomic<std::uint64_t> written_{0};
  std::atomic<std::uint64_t> offered_{0};
  std::atomic<bool> closing_{false};
  std::string error_;  // first failed commit of this stream's chunks (guarded by streams_mu_)
  // Writer-thread state: the chunk being filled.
  std::vector<float> pending_;
  double pending_start_s_ = 0;
  double last_t_s_ = 0;
  std::size_t pending_count_ = 0;
  TripleBuffer<TrajectorySample> latest_{TrajectorySample{-1.0, {}}};  // writer -> Latest()
};

/// Owns a database connection and a thread that drains every open stream into
/// `trajectory_chunk` rows. A chunk is cut when it is full or when the sample times are not
/// contiguous at the stream's rate (a dropped sample starts a new chunk), so every sample's
/// time is start_time_s + i / rate_hz.
///
/// Chunks are tagged with the trial's current attempt (read from the database when the
/// stream opens, so a stream opened after Database::StartTrial belongs to that attempt). A
/// failed commit (disk full, a lock held too long) keeps its chunks for a retry; what is
/// still not committed when the stream closes is reported, so the trial is not completed
/// (Database::CompleteTrial with TakeReports). Nothing is lost silently.
class TrajectoryWriter {
 public:
  explicit TrajectoryWriter(const std::string& db_path, const WriterOptions& options = {});
  ~TrajectoryWriter();  ///< writes everything queued, then stops
  TrajectoryWriter(const TrajectoryWriter&) = delete;
  TrajectoryWriter& operator=(const TrajectoryWriter&) = delete;

  /// Registers a stream (not real-time: allocates, reads the trial's current attempt from
  /// the database). The returned pointer stays valid until CloseStream or the writer's
  /// destruction.
  /// @param rate_hz nominal sample rate [Hz], > 0
  /// @param channels channel names with units (1..kMaxChannels), e.g. {"x_m", "fz_N"}
  TrajectoryStream* OpenStream(std::int64_t trial_id, const std::string& name, double rate_hz,
                               const std::vector<std::string>& channels);
  /// Writes what the stream queued and forgets it. Blocks until written (or failed).
  /// Returns the stream's report, which is also kept for TakeReports.
  StreamReport CloseStream(TrajectoryStream* stream);
  /// Reports of the closed streams of a trial (all attempts), removed from the writer.
  std::vector<StreamReport> TakeReports(std::int64_t trial_id);
  /// Blocks until every sample queued before the call is committed.
  void Flush();
  void Start();

  /// Samples committed to the database so far, over all streams.
  std::uint64_t written_samples() const { return written_.load(std::memory_order_relaxed); }
  /// Chunks committed so far.
  std::uint64_t written_chunks() const { return chunks_.load(std::memory_order_relaxed); }
  /// The first error the writer thread met (empty when none; it stays set after a retry
  /// succeeded). After an error the writer keeps draining queues so producers never stall
  /// and retries the failed chunks; each stream's report says what was finally committed.
  std::string error() const;

 private:
  void Run();
  // Drains queues; returns samples moved. Commits full chunks (and all pending when `all`).
  std::size_t Pass(bool all);

  struct Impl;
  std::unique_ptr<Impl> impl_;
  WriterOptions options_;
  struct Retry {
    TrajectoryChunk chunk;
    TrajectoryStream* origin = nullptr;
  };
  std::mutex streams_mu_;  // guards streams_, retry_, reports_ and each stream's error_
  std::vector<std::unique_ptr<TrajectoryStream>> streams_;
  std::vector<Retry> retry_;           // chunks whose commit failed, oldest first
  std::vector<StreamReport> reports_;  // closed streams not yet taken
  std::mutex reader_mu_;               // guards Impl::reader (OpenStream callers)
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> flush_requests_{0};
  std::atomic<std::uint64_t> flush_done_{0};
  std::atomic<std::uint64_t> written_{0};
  std::atomic<std::uint64_t> chunks_{0};
  std::atomic<bool> failing_{false};  // the last commit failed; chunks wait in retry_
  mutable std::mutex error_mu_;
  std::string error_;
  std::thread thread_;
};

}  // namespace hapticlab::db
