#include "hapticlab/db/trajectory_writer.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "hapticlab/core/status.hpp"
#include "hapticlab/db/database.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db {

struct TrajectoryWriter::Impl {
  Impl(const std::string& path, int busy_timeout_ms)
      : db(path, {.busy_timeout_ms = busy_timeout_ms}),
        reader(path, {.create = false, .read_only = true, .busy_timeout_ms = busy_timeout_ms}) {}
  Database db;      // the writer thread's connection
  Database reader;  // OpenStream's (caller thread) connection: reads a trial's attempt
};

TrajectoryStream::TrajectoryStream(std::int64_t trial_id, int attempt, std::string name,
                                   double rate_hz, std::vector<std::string> channels,
                                   std::size_t capacity)
    : trial_id_(trial_id),
      attempt_(attempt),
      name_(std::move(name)),
      rate_hz_(rate_hz),
      channel_names_(std::move(channels)),
      channels_(channel_names_.size()),
      queue_(capacity) {}

TrajectoryWriter::TrajectoryWriter(const std::string& db_path, const WriterOptions& options)
    : impl_(std::make_unique<Impl>(db_path, options.busy_timeout_ms)), options_(options) {
  HL_REQUIRE(options.chunk_samples >= 1, "chunk_samples must be at least 1");
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
  HL_REQUIRE(rate_hz > 0 && std::isfinite(rate_hz), "stream rate must be positive");
  HL_REQUIRE(!channels.empty() && channels.size() <= kMaxChannels, "a stream has 1 to 16 channels");
  HL_REQUIRE(!name.empty(), "stream name must not be empty");
  int attempt = 0;
  {
    std::lock_guard lock(reader_mu_);
    attempt = impl_->reader.CurrentAttempt(trial_id);
  }
  auto s = std::unique_ptr<TrajectoryStream>(
      new TrajectoryStream(trial_id, attempt, name, rate_hz, channels, options_.queue_capacity));
  s->pending_.reserve(options_.chunk_samples * channels.size());
  std::lock_guard lock(streams_mu_);
  streams_.push_back(std::move(s));
  return streams_.back().get();
}

StreamReport TrajectoryWriter::CloseStream(TrajectoryStream* stream) {
  stream->closing_.store(true);
  Flush();
  std::lock_guard lock(streams_mu_);
  // Chunks still waiting for a retry are lost to this attempt; the report shows it.
  std::size_t waiting = 0;
  for (const auto& r : retry_) waiting += r.origin == stream;
  std::erase_if(retry_, [&](const Retry& r) { return r.origin == stream; });
  StreamReport rep;
  rep.trial_id = stream->trial_id_;
  rep.attempt = stream->attempt_;
  rep.stream = stream->name_;
  rep.rate_hz = stream->rate_hz_;
  rep.samples_offered = stream->offered_count();
  rep.samples_dropped = stream->overflow_count();
  rep.samples_written = stream->written_count();
  rep.error = stream->error_;
  if (waiting > 0 && rep.error.empty()) rep.error = "chunks not committed when the stream closed";
  reports_.push_back(rep);
  std::erase_if(streams_, [&](const auto& p) { return p.get() == stream; });
  return rep;
}

std::vector<StreamReport> TrajectoryWriter::TakeReports(std::int64_t trial_id) {
  std::lock_guard lock(streams_mu_);
  std::vector<StreamReport> out;
  for (const auto& r : reports_)
    if (r.trial_id == trial_id) out.push_back(r);
  std::erase_if(reports_, [&](const StreamReport& r) { return r.trial_id == trial_id; });
  return out;
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
  std::size_t moved = 0;
  std::lock_guard lock(streams_mu_);
  // Chunks of earlier failed commits go first, so a stream's chunks commit in order.
  std::vector<Retry> ready = std::move(retry_);
  retry_.clear();
  auto cut = [&](TrajectoryStream& s) {
    if (s.pending_count_ == 0) return;
    TrajectoryChunk c;
    c.trial_id = s.trial_id_;
    c.attempt = s.attempt_;
    c.stream = s.name_;
    c.start_time_s = s.pending_start_s_;
    c.rate_hz = s.rate_hz_;
    c.channels = s.channel_names_;
    c.samples.assign(s.pending_.begin(), s.pending_.end());
    ready.push_back({std::move(c), &s});
    s.pending_.clear();
    s.pending_count_ = 0;
  };
  for (auto& sp : streams_) {
    TrajectoryStream& s = *sp;
    const double period = 1.0 / s.rate_hz_;
    TrajectorySample x{};
    bool popped = false;
    while (s.queue_.TryPop(&x)) {
      ++moved;
      popped = true;
      // A gap (dropped samples, pause) or a step back in time starts a new chunk.
      if (s.pending_count_ > 0 && std::abs(x.t_s - (s.last_t_s_ + period)) > 0.5 * period) cut(s);
      if (s.pending_count_ == 0) s.pending_start_s_ = x.t_s;
      s.pending_.insert(s.pending_.end(), x.values.begin(), x.values.begin() + s.channels_);
      s.last_t_s_ = x.t_s;
      if (++s.pending_count_ >= options_.chunk_samples) cut(s);
    }
    if (popped) {  // the newest recorded sample, for a live display (TrajectoryStream::Latest)
      s.latest_.WriteSlot() = x;
      s.latest_.Publish();
    }
    if (all || s.closing_.load()) cut(s);
  }
  if (ready.empty()) return moved;
  try {
    internal::Transaction tx(impl_->db.handle());
    for (const auto& r : ready) impl_->db.InsertTrajectoryChunk(r.chunk);
    tx.Commit();
    std::uint64_t n = 0;
    for (const auto& r : ready) {
      n += r.chunk.sample_count();
      r.origin->written_.fetch_add(r.chunk.sample_count());
    }
    written_.fetch_add(n);
    chunks_.fetch_add(ready.size());
    failing_.store(false);
  } catch (const std::exception& e) {
    {
      std::lock_guard elock(error_mu_);
      if (error_.empty()) error_ = e.what();
    }
    for (auto& r : ready)
      if (r.origin->error_.empty()) r.origin->error_ = e.what();
    // Keep the chunks for the next pass; past the limit the oldest are dropped (their
    // streams report the loss when they close).
    std::size_t values = 0;
    for (const auto& r : ready) values += r.chunk.samples.size();
    std::size_t first = 0;
    while (first < ready.size() && values > options_.retry_limit_values) {
      values -= ready[first].chunk.samples.size();
      ++first;
    }
    failing_.store(true);
    retry_.assign(std::make_move_iterator(ready.begin() + static_cast<std::ptrdiff_t>(first)),
                  std::make_move_iterator(ready.end()));
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
    // After a failed commit, retry every 20 ms rather than spin on a full disk.
    if (moved == 0)
      std::this_thread::sleep_for(std::chrono::milliseconds(failing_.load() ? 20 : 1));
  }
}

}  // namespace hapticlab::db
