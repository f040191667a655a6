#include "hapticlab/db/export.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db {
namespace {

using internal::Stmt;

class CsvOut {
 public:
  explicit CsvOut(const std::string& path) : path_(path), f_(path) {
    if (!f_) throw std::runtime_error(path + ": cannot write");
  }
  void Row(const std::vector<std::string>& cells) {
    for (std::size_t i = 0; i < cells.size(); ++i) f_ << (i ? "," : "") << CsvEscape(cells[i]);
    f_ << '\n';
    ++rows_;
  }
  ExportedFile Close() {
    f_.close();
    if (!f_) throw std::runtime_error(path_ + ": write failed");
    return {path_, rows_ == 0 ? 0 : rows_ - 1};
  }

 private:
  std::string path_;
  std::ofstream f_;
  std::size_t rows_ = 0;
};

std::string Num(double v) { return fmt::format("{:.17g}", v); }
std::string F32(float v) { return fmt::format("{:.9g}", v); }

// Joins trial -> session -> participant -> study once for every table.
constexpr const char* kTrialJoin =
    " FROM trial t JOIN session s ON t.session_id = s.id JOIN participant p ON "
    "s.participant_id = p.id JOIN study st ON p.study_id = st.id ";

}  // namespace

std::vector<ExportedFile> ExportCsv(const Database& db, const std::string& out_dir,
                                    bool trajectories) {
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
    out.Row({"study", "participant", "session_id", "trial", "kind", "detail", "created_at"});
    Stmt q(h,
           "SELECT st.name, p.code, e.session_id, t.plan_index + 1, e.kind, e.detail, "
           "e.created_at FROM event e JOIN session s ON e.session_id = s.id JOIN participant p ON "
           "s.participant_id = p.id JOIN study st ON p.study_id = st.id LEFT JOIN trial t ON "
           "t.id = e.trial_id ORDER BY e.id");
    while (q.Step())
      out.Row({q.Text(0), q.Text(1), std::to_string(q.Int(2)),
               q.IsNull(3) ? std::string() : std::to_string(q.Int(3)), q.Text(4), q.Text(5),
               q.Text(6)});
    files.push_back(out.Close());
  }
  if (trajectories) {
    // Only completed trials' completing attempts, and only when their stored sample-count
    // checks still hold.
    if (const auto problems = db.VerifyTrajectories(); !problems.empty())
      throw InputError(db.path(), 0, "trajectory_chunk",
                       fmt::format("trajectories do not match the sample counts stored at "
                                   "completion, export refused: {}",
                                   fmt::join(problems, "; ")));
    // One file per (stream, channel layout); a second layout of one stream name gets a suffix.
    std::map<std::pair<std::string, std::string>, std::unique_ptr<CsvOut>> outs;
    std::map<std::string, int> layouts_per_stream;
    Stmt q(h,
           (std::string("SELECT st.name, p.code, t.plan_index + 1, c.stream, c.channels, "
                        "c.start_time_s, c.rate_hz, c.sample_count, c.samples") +
            kTrialJoin +
            "JOIN trajectory_chunk c ON c.trial_id = t.id AND c.attempt = t.completed_attempt "
            "WHERE t.status = 'completed' ORDER BY c.stream, s.id, t.plan_index, c.start_time_s, "
            "c.id")
               .c_str());
    std::vector<float> buf;
    while (q.Step()) {
      const std::string stream = q.Text(3);
      const std::string layout = q.Text(4);
      auto& out = outs[{stream, layout}];
      std::vector<std::string> channels;
      {
        std::size_t a = 0;
        while (a <= layout.size()) {
          const auto b = layout.find(',', a);
          channels.push_back(layout.substr(a, b == std::string::npos ? std::string::npos : b - a));
          if (b == std::string::npos) break;
          a = b + 1;
        }
      }
      if (!out) {
        const int n = ++layouts_per_stream[stream];
        std::string name = "trajectory_" + stream + (n > 1 ? "_" + std::to_string(n) : "") + ".csv";
        out = std::make_unique<CsvOut>((fs::path(out_dir) / name).string());
        std::vector<std::string> header{"study", "participant", "trial", "t_s"};
        header.insert(header.end(), channels.begin(), channels.end());
        out->Row(header);
      }
      const double t0 = q.Real(5);
      const double rate = q.Real(6);
      const auto nc = channels.size();
      const std::int64_t count = q.Int(7);
      if (count < 0 || static_cast<std::size_t>(q.BlobBytes(8)) !=
                           static_cast<std::size_t>(count) * nc * sizeof(float))
        throw InputError(db.path(), 0, "trajectory_chunk",
                         fmt::format("trial {} stream {}: a chunk's samples do not match its "
                                     "sample count ({} bytes for {} samples of {} channels)",
                                     q.Int(2), stream, q.BlobBytes(8), count, nc));
      const auto n = static_cast<std::size_t>(count);
      buf.resize(n * nc);
      if (!buf.empty()) std::memcpy(buf.data(), q.Blob(8), buf.size() * sizeof(float));
      std::vector<std::string> row(4 + nc);
      row[0] = q.Text(0);
      row[1] = q.Text(1);
      row[2] = std::to_string(q.Int(2));
      for (std::size_t i = 0; i < n; ++i) {
        row[3] = Num(t0 + static_cast<double>(i) / rate);
        for (std::size_t c = 0; c < nc; ++c) row[4 + c] = F32(buf[i * nc + c]);
        out->Row(row);
      }
    }
    for (auto& [key, out] : outs) files.push_back(out->Close());
  }
  return files;
}

}  // namespace hapticlab::db
