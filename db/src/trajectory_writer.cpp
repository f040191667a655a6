#include "hapticlab/db/trajectory_writer.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "hapticlab/core/status.hpp"
#include "hapticlab/db/database.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db {

struct TrajectoryWriter::Impl {
  explicit Impl(const std::string& path) : db(path) {}
  Database db;
};

TrajectoryStream::TrajectoryStream(std::int64_t trial_id, std::string name, double rate_hz,
                                   std::vector<std::string> channels, std::size_t capacity)
    : trial_id_(trial_id),
      name_(std::move(name)),
      rate_hz_(rate_hz),
      channel_names_(std::move(channels)),
      channels_(channel_names_.size()),
      queue_(capacity) {}

TrajectoryWriter::TrajectoryWriter(const std::string& db_path, const WriterOptions& options)
    : impl_(std::make_unique<Impl>(db_path)), options_(options) {
  HL_THROW_UNLESS(options.chunk_samples >= 1, "chunk_samples must be at least 1");
  if (options.start_thread) Start();
}

TrajectoryWriter::~TrajectoryWriter() {
  if (!thread_.joinable()) Start();  // drain what was queued even if never started
  stop_.store(true);
  thread_.join();
}

void TrajectoryWriter::Start() {
  if (!thread_.joinable()) thread_ = std::thread([this] { Run(); });
}

TrajectoryStream* TrajectoryWriter::OpenStream(std::int64_t trial_id, const std::string& name,
                                               double rate_hz,
                                               const std::vector<std::string>& channels) {
  HL_THROW_UNLESS(rate_hz > 0 && std::isfinite(rate_hz), "stream rate must be positive");
  HL_THROW_UNLESS(!channels.empty() && channels.size() <= kMaxChannels,
                  "a stream has 1 to 16 channels");
  HL_THROW_UNLESS(!name.empty(), "stream name must not be empty");
  auto s = std::unique_ptr<TrajectoryStream>(
      new TrajectoryStream(trial_id, name, rate_hz, channels, options_.queue_capacity));
  s->pending_.reserve(options_.chunk_samples * channels.size());
  std::lock_guard lock(streams_mu_);
  streams_.push_back(std::move(s));
  return streams_.back().get();
}

void TrajectoryWriter::CloseStream(TrajectoryStream* stream) {
  stream->closing_.store(true);
  Flush();
  std::lock_guard lock(streams_mu_);
  for (auto it = streams_.begin(); it != streams_.end(); ++it) {
    if (it->get() == stream) {
      streams_.erase(it);
      return;
    }
  }
}

void TrajectoryWriter::Flush() {
  Start();
  const auto ticket = flush_requests_.fetch_add(1) + 1;
  while (flush_done_.load() < ticket) std::this_thread::sleep_for(std::chrono::microseconds(200));
}

std::string TrajectoryWriter::error() const {
  std::lock_guard lock(error_mu_);
  return error_;
}

std::size_t TrajectoryWriter::Pass(bool all) {
  std::vector<TrajectoryChunk> ready;
  std::size_t moved = 0;
  std::lock_guard lock(streams_mu_);
  auto cut = [&](TrajectoryStream& s) {
    if (s.pending_count_ == 0) return;
    TrajectoryChunk c;
    c.trial_id = s.trial_id_;
    c.stream = s.name_;
    c.start_time_s = s.pending_start_s_;
    c.rate_hz = s.rate_hz_;
    c.channels = s.channel_names_;
    c.samples.assign(s.pending_.begin(), s.pending_.end());
    ready.push_back(std::move(c));
    s.pending_.clear();
    s.pending_count_ = 0;
  };
  for (auto& sp : streams_) {
    TrajectoryStream& s = *sp;
    const double period = 1.0 / s.rate_hz_;
    TrajectorySample x;
    while (s.queue_.TryPop(&x)) {
      ++moved;
      // A gap (dropped samples, pause) or a step back in time starts a new chunk.
      if (s.pending_count_ > 0 && std::abs(x.t_s - (s.last_t_s_ + period)) > 0.5 * period) cut(s);
      if (s.pending_count_ == 0) s.pending_start_s_ = x.t_s;
      s.pending_.insert(s.pending_.end(), x.values.begin(), x.values.begin() + s.channels_);
      s.last_t_s_ = x.t_s;
      if (++s.pending_count_ >= options_.chunk_samples) cut(s);
    }
    if (all || s.closing_.load()) cut(s);
  }
  if (ready.empty()) return moved;
  try {
    internal::Transaction tx(impl_->db.handle());
    for (const auto& c : ready) impl_->db.InsertTrajectoryChunk(c);
    tx.Commit();
    std::uint64_t n = 0;
    for (const auto& c : ready) n += c.sample_count();
    written_.fetch_add(n);
    chunks_.fetch_add(ready.size());
    for (auto& sp : streams_)
      for (const auto& c : ready)
        if (c.trial_id == sp->trial_id_ && c.stream == sp->name_)
          sp->written_.fetch_add(c.sample_count());
  } catch (const std::exception& e) {
    std::lock_guard elock(error_mu_);
    if (error_.empty()) error_ = e.what();
  }
  return moved;
}

void TrajectoryWriter::Run() {
  for (;;) {
    const bool stopping = stop_.load();
    const auto requested = flush_requests_.load();
    const std::size_t moved = Pass(stopping || requested != flush_done_.load());
    if (requested != flush_done_.load()) {
      // Everything queued before the request has now been popped and committed.
      Pass(true);
      flush_done_.store(requested);
    }
    if (stopping) {
      Pass(true);
      return;
    }
    if (moved == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

}  // namespace hapticlab::db
