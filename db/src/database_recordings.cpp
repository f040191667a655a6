// Database: material models, measurements and trajectory chunks.
#include <fcntl.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <openssl/evp.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/db/database.hpp"
#include "schema.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db {

using internal::Stmt;

namespace {

std::string JoinChannels(const std::vector<std::string>& c) {
  std::string s;
  for (const auto& x : c) s += (s.empty() ? "" : ",") + x;
  return s;
}

std::vector<std::string> SplitChannels(const std::string& s) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= s.size()) {
    const auto comma = s.find(',', start);
    const auto end = comma == std::string::npos ? s.size() : comma;
    if (end > start) out.push_back(s.substr(start, end - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace

std::int64_t Database::SaveMaterialModel(const std::string& name, const std::string& toml_text) {
  const std::string hash = HashText(toml_text);
  Stmt f(db_, "SELECT id FROM material_model WHERE name=? AND hash=?");
  f.Bind(1, name).Bind(2, hash);
  if (f.Step()) return f.Int(0);
  Stmt s(db_, "INSERT INTO material_model(name, hash, toml) VALUES (?,?,?)");
  s.Bind(1, name).Bind(2, hash).Bind(3, toml_text).Run();
  return sqlite3_last_insert_rowid(db_);
}

void Database::InsertTrajectoryChunk(const TrajectoryChunk& c) {
  HL_REQUIRE(c.attempt >= 0, "trajectory chunk attempt must not be negative");
  HL_REQUIRE(!c.channels.empty(), "trajectory chunk needs at least one channel");
  HL_REQUIRE(c.samples.size() % c.channels.size() == 0,
             "trajectory chunk sample count is not a multiple of its channel count");
  HL_REQUIRE(c.rate_hz > 0, "trajectory chunk rate must be positive");
  Stmt s(db_,
         "INSERT INTO trajectory_chunk(trial_id, stream, start_time_s, rate_hz, channels, "
         "sample_count, samples, attempt) VALUES (?,?,?,?,?,?,?,?)");
  s.Bind(1, c.trial_id)
      .Bind(2, c.stream)
      .Bind(3, c.start_time_s)
      .Bind(4, c.rate_hz)
      .Bind(5, JoinChannels(c.channels))
      .Bind(6, static_cast<std::int64_t>(c.sample_count()))
      .BindBlob(7, c.samples.data(), c.samples.size() * sizeof(float))
      .Bind(8, c.attempt)
      .Run();
}

std::vector<TrajectoryChunk> Database::TrajectoryChunks(std::int64_t trial_id) const {
  Stmt a(db_, "SELECT coalesce(completed_attempt, attempts) FROM trial WHERE id=?");
  a.Bind(1, trial_id);
  if (!a.Step()) return {};
  return TrajectoryChunks(trial_id, static_cast<int>(a.Int(0)));
}

std::vector<TrajectoryChunk> Database::TrajectoryChunks(std::int64_t trial_id, int attempt) const {
  Stmt s(db_,
         "SELECT trial_id, stream, start_time_s, rate_hz, channels, sample_count, samples, attempt "
         "FROM trajectory_chunk WHERE trial_id=? AND attempt=? ORDER BY stream, start_time_s, id");
  s.Bind(1, trial_id).Bind(2, attempt);
  std::vector<TrajectoryChunk> out;
  while (s.Step()) {
    TrajectoryChunk c;
    c.trial_id = s.Int(0);
    c.stream = s.Text(1);
    c.start_time_s = s.Real(2);
    c.rate_hz = s.Real(3);
    c.channels = SplitChannels(s.Text(4));
    c.attempt = static_cast<int>(s.Int(7));
    const auto bytes = static_cast<std::size_t>(s.BlobBytes(6));
    // A blob that does not match its row's sample and channel counts is damage, not data.
    if (c.channels.empty() || s.Int(5) < 0 ||
        bytes != static_cast<std::size_t>(s.Int(5)) * c.channels.size() * sizeof(float))
      throw std::runtime_error(fmt::format(
          "{}: trajectory chunk of trial {} stream {} is damaged ({} bytes for {} samples of {} "
          "channels)",
          path_, trial_id, c.stream, bytes, s.Int(5), c.channels.size()));
    c.samples.resize(bytes / sizeof(float));
    if (bytes) std::memcpy(c.samples.data(), s.Blob(6), bytes);
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace hapticlab::db
