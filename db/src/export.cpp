#include "hapticlab/db/export.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/export_formats.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db {
namespace {

using internal::Stmt;

// A CSV file written through one buffer, flushed in blocks of about 1 MiB: the trajectory
// tables hold millions of rows, and a stream insertion per cell made them slow (issue #32).
class CsvOut {
 public:
  explicit CsvOut(std::string path) : path_(std::move(path)), f_(std::fopen(path_.c_str(), "wb")) {
    if (!f_) throw std::runtime_error(path_ + ": cannot write");
  }
  ~CsvOut() {
    if (f_) std::fclose(f_);
  }
  CsvOut(const CsvOut&) = delete;
  CsvOut& operator=(const CsvOut&) = delete;
  void Row(const std::vector<std::string>& cells) {
    for (std::size_t i = 0; i < cells.size(); ++i) buf_ += (i ? "," : "") + CsvEscape(cells[i]);
    EndRow();
  }
  /// The row being written: append its cells (already escaped), then EndRow().
  std::string& buffer() { return buf_; }
  void EndRow() {
    buf_ += '\n';
    ++rows_;
    if (buf_.size() > (1u << 20)) Flush();
  }
  ExportedFile Close() {
    Flush();
    const int rc = std::fclose(f_);
    f_ = nullptr;
    if (rc != 0) throw std::runtime_error(path_ + ": write failed");
    return {.path = path_, .rows = rows_ == 0 ? 0 : rows_ - 1};
  }

 private:
  void Flush() {
    if (!buf_.empty() && std::fwrite(buf_.data(), 1, buf_.size(), f_) != buf_.size())
      throw std::runtime_error(path_ + ": write failed");
    buf_.clear();
  }
  std::string path_;
  std::FILE* f_;
  std::string buf_;
  std::size_t rows_ = 0;
};

std::string Num(double v) { return fmt::format("{:.17g}", v); }

// Bytes per sample value in the trajectory CSVs (a comma and the shortest float text),
// measured on the demo's database (docs/performance.md); CountTrajectories' estimate.
constexpr double kBytesPerValue = 10.5;

// Joins trial -> session -> participant -> study once for every table.
constexpr const char* kTrialJoin =
    " FROM trial t JOIN session s ON t.session_id = s.id JOIN participant p ON "
    "s.participant_id = p.id JOIN study st ON p.study_id = st.id ";

std::vector<std::string> SplitLayout(const std::string& layout) {
  std::vector<std::string> channels;
  std::size_t a = 0;
  while (a <= layout.size()) {
    const auto b = layout.find(',', a);
    channels.push_back(layout.substr(a, b == std::string::npos ? std::string::npos : b - a));
    if (b == std::string::npos) break;
    a = b + 1;
  }
  return channels;
}

// One file per (stream, channel layout), a second layout of one stream name with a suffix;
// rows per participant (in study, participant order), then trial, then time.
class TrajectoryTables {
 public:
  TrajectoryTables(const Database& db, std::string out_dir)
      : db_(db), out_dir_(std::move(out_dir)) {}

  // Writes one chunk's samples: `keys` is the row's escaped "study,participant,trial,".
  void Chunk(Stmt& q, const std::string& keys) {
    const std::string stream = q.Text(1), layout = q.Text(2);
    auto& out = outs_[{stream, layout}];
    const auto channels = SplitLayout(layout);
    if (!out) {
      const int n = ++layouts_per_stream_[stream];
      std::string name = "trajectory_" + stream + (n > 1 ? "_" + std::to_string(n) : "") + ".csv";
      out = std::make_unique<CsvOut>((std::filesystem::path(out_dir_) / name).string());
      std::vector<std::string> header{"study", "participant", "trial", "t_s"};
      header.insert(header.end(), channels.begin(), channels.end());
      out->Row(header);
    }
    const double t0 = q.Real(3), rate = q.Real(4);
    const auto nc = channels.size();
    const std::int64_t count = q.Int(5);
    if (count < 0 || static_cast<std::size_t>(q.BlobBytes(6)) !=
                         static_cast<std::size_t>(count) * nc * sizeof(float))
      throw InputError(db_.path(), 0, "trajectory_chunk",
                       fmt::format("trial {} stream {}: a chunk's samples do not match its "
                                   "sample count ({} bytes for {} samples of {} channels)",
                                   q.Int(0), stream, q.BlobBytes(6), count, nc));
    const auto n = static_cast<std::size_t>(count);
    buf_.resize(n * nc);
    if (!buf_.empty()) std::memcpy(buf_.data(), q.Blob(6), buf_.size() * sizeof(float));
    // The shortest text that reads back as the same double (time) and float32 (samples).
    std::string& b = out->buffer();
    for (std::size_t i = 0; i < n; ++i) {
      b += keys;
      fmt::format_to(std::back_inserter(b), "{}", t0 + static_cast<double>(i) / rate);
      for (std::size_t c = 0; c < nc; ++c)
        fmt::format_to(std::back_inserter(b), ",{}", buf_[i * nc + c]);
      out->EndRow();
    }
    samples_ += n;
  }
  std::size_t samples() const { return samples_; }
  std::vector<ExportedFile> Close() {
    std::vector<ExportedFile> files;
    for (auto& [key, out] : outs_) files.push_back(out->Close());
    return files;
  }

 private:
  const Database& db_;
  std::string out_dir_;
  std::map<std::pair<std::string, std::string>, std::unique_ptr<CsvOut>> outs_;
  std::map<std::string, int> layouts_per_stream_;
  std::vector<float> buf_;
  std::size_t samples_ = 0;
};

// Only completed trials' completing attempts, and only when their stored sample-count checks
// still hold.
std::vector<ExportedFile> WriteTrajectories(const Database& db, const std::string& out_dir,
                                            const ExportProgress& progress) {
  if (const auto problems = db.VerifyTrajectories(); !problems.empty())
    throw InputError(db.path(), 0, "trajectory_chunk",
                     fmt::format("trajectories do not match the sample counts stored at "
                                 "completion, export refused: {}",
                                 fmt::join(problems, "; ")));
  TrajectoryTables tables(db, out_dir);
  Stmt who(db.handle(),
           "SELECT p.id, p.code, st.name FROM participant p JOIN study st ON p.study_id = st.id "
           "ORDER BY st.id, p.id");
  while (who.Step()) {
    Stmt q(db.handle(),
           "SELECT t.plan_index + 1, c.stream, c.channels, c.start_time_s, c.rate_hz, "
           "c.sample_count, c.samples FROM session s JOIN trial t ON t.session_id = s.id JOIN "
           "trajectory_chunk c ON c.trial_id = t.id AND c.attempt = t.completed_attempt WHERE "
           "s.participant_id = ? AND t.status = 'completed' ORDER BY t.plan_index, c.stream, "
           "c.start_time_s, c.id");
    q.Bind(1, who.Int(0));
    const std::string prefix = CsvEscape(who.Text(2)) + "," + CsvEscape(who.Text(1)) + ",";
    const std::size_t before = tables.samples();
    std::set<std::int64_t> trials;
    while (q.Step()) {
      trials.insert(q.Int(0));
      tables.Chunk(q, prefix + std::to_string(q.Int(0)) + ",");
    }
    if (progress)
      progress(fmt::format("{} ({}): {} trajectory samples of {} trials", who.Text(1), who.Text(2),
                           tables.samples() - before, trials.size()));
  }
  return tables.Close();
}

}  // namespace

std::vector<ExportedFile> ExportCsv(const Database& db, const std::string& out_dir,
                                    bool trajectories, const ExportProgress& progress) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) throw std::runtime_error(out_dir + ": cannot create directory: " + ec.message());
  std::vector<ExportedFile> files;
  sqlite3* h = db.handle();

  {
    CsvOut out((fs::path(out_dir) / "ratings.csv").string());
    out.Row({"study", "participant", "session_id", "trial", "phase", "material", "comparison",
             "method", "repetition", "left", "right", "criterion", "score", "response_time_s",
             "source"});
    Stmt q(h, (std::string("SELECT st.name, p.code, s.id, t.plan_index + 1, t.phase, "
                           "t.material, t.comparison, t.method, t.repetition, t.left_stimulus, "
                           "t.right_stimulus, r.criterion, r.score, r.response_time_s, r.source") +
               kTrialJoin + "JOIN rating r ON r.trial_id = t.id ORDER BY s.id, t.plan_index, r.id")
                  .c_str());
    while (q.Step())
      out.Row({q.Text(0), q.Text(1), std::to_string(q.Int(2)), std::to_string(q.Int(3)), q.Text(4),
               q.Text(5), q.Text(6), q.Text(7), std::to_string(q.Int(8)), q.Text(9), q.Text(10),
               q.Text(11), Num(q.Real(12)), Num(q.Real(13)), q.Text(14)});
    files.push_back(out.Close());
  }
  {
    CsvOut out((fs::path(out_dir) / "trials.csv").string());
    out.Row({"study", "participant", "session_id", "trial", "phase", "material", "comparison",
             "method", "repetition", "left", "right", "status", "attempts", "started_at",
             "completed_at"});
    Stmt q(h, (std::string("SELECT st.name, p.code, s.id, t.plan_index + 1, t.phase, "
                           "t.material, t.comparison, t.method, t.repetition, t.left_stimulus, "
                           "t.right_stimulus, t.status, t.attempts, coalesce(t.started_at,''), "
                           "coalesce(t.completed_at,'')") +
               kTrialJoin + "ORDER BY s.id, t.plan_index, t.id")
                  .c_str());
    while (q.Step())
      out.Row({q.Text(0), q.Text(1), std::to_string(q.Int(2)), std::to_string(q.Int(3)), q.Text(4),
               q.Text(5), q.Text(6), q.Text(7), std::to_string(q.Int(8)), q.Text(9), q.Text(10),
               q.Text(11), std::to_string(q.Int(12)), q.Text(13), q.Text(14)});
    files.push_back(out.Close());
  }
  {
    CsvOut out((fs::path(out_dir) / "events.csv").string());
    out.Row({"study", "participant", "session_id", "trial", "kind", "detail", "created_at",
             "established_by"});
    Stmt q(h,
           "SELECT st.name, p.code, e.session_id, t.plan_index + 1, e.kind, e.detail, "
           "e.created_at, e.established_by FROM event e JOIN session s ON e.session_id = s.id "
           "JOIN participant p ON s.participant_id = p.id JOIN study st ON p.study_id = st.id "
           "LEFT JOIN trial t ON t.id = e.trial_id ORDER BY e.id");
    while (q.Step())
      out.Row({q.Text(0), q.Text(1), std::to_string(q.Int(2)),
               q.IsNull(3) ? std::string() : std::to_string(q.Int(3)), q.Text(4), q.Text(5),
               q.Text(6), q.Text(7)});
    files.push_back(out.Close());
  }
  if (trajectories) {
    auto t = WriteTrajectories(db, out_dir, progress);
    files.insert(files.end(), t.begin(), t.end());
  }
  return files;
}

TrajectorySize CountTrajectories(const Database& db) {
  // Channels per chunk = commas in the layout + 1; keys per row ~ study, code, trial id.
  Stmt q(db.handle(),
         "SELECT count(DISTINCT c.stream), coalesce(sum(c.sample_count), 0), "
         "coalesce(sum(c.sample_count * (length(c.channels) - length(replace(c.channels, ',', "
         "'')) + 1)), 0), coalesce(sum(c.sample_count * (length(st.name) + length(p.code) + 16)), "
         "0) FROM trajectory_chunk c JOIN trial t ON c.trial_id = t.id AND c.attempt = "
         "t.completed_attempt JOIN session s ON t.session_id = s.id JOIN participant p ON "
         "s.participant_id = p.id JOIN study st ON p.study_id = st.id WHERE t.status = "
         "'completed'");
  TrajectorySize z;
  if (q.Step()) {
    z.streams = static_cast<std::size_t>(q.Int(0));
    z.samples = static_cast<std::size_t>(q.Int(1));
    z.values = static_cast<std::size_t>(q.Int(2));
    z.estimated_bytes = static_cast<std::size_t>(static_cast<double>(q.Int(2)) * kBytesPerValue +
                                                 static_cast<double>(q.Int(3)));
  }
  return z;
}

ExportFormat CsvExportFormat() {
  ExportFormat f;
  f.name = "csv";
  f.help =
      "tidy long-format CSV tables (ratings, trials, events; with --trajectories one\n"
      "file per trajectory stream) that R's read.csv and pandas.read_csv read\n"
      "directly; --out DIR";
  f.chooses_trajectories = true;
  f.write = [](const Database& db, const ExportRequest& r) {
    // The trajectory tables can be hundreds of MB: their size is said before either choice.
    const auto size = CountTrajectories(db);
    const std::string what =
        fmt::format("{} samples of {} streams, about {:.1f} MB as CSV", size.samples, size.streams,
                    static_cast<double>(size.estimated_bytes) / 1e6);
    if (size.samples > 0 && r.progress)
      r.progress(r.trajectories
                     ? "writing trajectories: " + what
                     : "trajectories left out (" + what + "): --trajectories writes them");
    return ExportCsv(db, r.out, r.trajectories, r.progress);
  };
  f.describe = [](const std::vector<ExportedFile>& files) {
    std::size_t rows = 0;
    for (const auto& x : files) rows += x.rows;
    return fmt::format("{} tables, {} rows", files.size(), rows);
  };
  return f;
}

}  // namespace hapticlab::db
