// BIDS export: behavioural ratings as beh/*_beh.tsv, trajectories as physio recordings
// beside them, protocol and models under code/. docs/analysis.md says why physio and not
// motion.

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/version.hpp"
#include "hapticlab/db/export_formats.hpp"
#include "hapticlab/db/interchange.hpp"
#include "interchange_internal.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db {
namespace {

namespace fs = std::filesystem;
using internal::Alnum;
using internal::SessionRecord;
using nlohmann::ordered_json;

void WriteText(const fs::path& p, const std::string& text) { WriteTextFile(p.string(), text); }

void WriteJson(const fs::path& p, const ordered_json& j) { WriteText(p, j.dump(2) + "\n"); }

// A TSV cell: BIDS writes a missing value as n/a, and a cell holds no tab or newline.
std::string Cell(const std::string& s) {
  if (s.empty()) return "n/a";
  std::string o = s;
  for (auto& c : o)
    if (c == '\t' || c == '\n' || c == '\r') c = ' ';
  return o;
}
std::string Num(double v) { return fmt::format("{:.17g}", v); }

class GzOut {
 public:
  // Level 1, not zlib's default 6: the export's CPU time fell from 8.5 s to 2.8 s on the
  // demo's database together with the shortest float text, at 1.4 % less disk
  // (docs/performance.md, "Exports").
  explicit GzOut(const fs::path& p) : path_(p.string()), f_(gzopen(path_.c_str(), "wb1")) {
    if (!f_) throw std::runtime_error(path_ + ": cannot write");
  }
  ~GzOut() {
    if (f_) gzclose(f_);
  }
  GzOut(const GzOut&) = delete;
  GzOut& operator=(const GzOut&) = delete;
  void Write(const std::string& s) {
    if (!s.empty() &&
        gzwrite(f_, s.data(), static_cast<unsigned>(s.size())) != static_cast<int>(s.size()))
      throw std::runtime_error(path_ + ": write failed");
  }
  void Close() {
    const int rc = gzclose(f_);
    f_ = nullptr;
    if (rc != Z_OK) throw std::runtime_error(path_ + ": write failed");
  }

 private:
  std::string path_;
  gzFile f_;
};

constexpr const char* kReadme =
    "This dataset was written by HapticLab (`hapticlab export --format bids`) from a study\n"
    "database. Each participant is known only by a pseudonymous code.\n\n"
    "- `sub-*/ses-*/beh/*_beh.tsv`: one row per rating, with the trial's conditions\n"
    "  (columns described in the matching `_beh.json`).\n"
    "- `sub-*/ses-*/beh/*_run-<n>_recording-<stream>_physio.tsv.gz`: the force and vibration\n"
    "  trajectories of trial n (the `trial` column of `_beh.tsv`: the trial's 1-based number\n"
    "  in the participant's plan), one file per recorded stream, time zero at the start of that "
    "stimulus\n"
    "  (the left stimulus, then the right one). Units and channel meanings in the `.json`\n"
    "  sidecars. Samples missing inside a recording are `n/a`.\n"
    "- `code/`: the study protocols and any material models stored in the database, with\n"
    "  their SHA-256 in `code/hashes.tsv`.\n"
    "Only completed trials are included.\n";

ordered_json BehSidecar(const SessionRecord& s) {
  ordered_json j;
  j["TaskName"] = s.study.name;
  j["TaskDescription"] =
      "Psychophysical haptic texture study: the participant strokes two stimuli (left, then right) "
      "with a "
      "stylus and rates them on the protocol's criteria.";
  j["trial"] = {{"Description",
                 "the trial's number in the participant's resolved plan (from 1, as HapticLab's "
                 "plan, log and console number it); physio recordings of the trial carry "
                 "run-<trial>"}};
  j["phase"] = {{"Description", "study phase"},
                {"Levels",
                 {{"training", "familiarisation"},
                  {"reference", "real-real pairs"},
                  {"main", "rated comparisons"}}}};
  j["material"] = {{"Description", "material shown (real sample id or virtual model)"}};
  j["comparison"] = {
      {"Description", "the other stimulus: 'virtual', or a material for real-real pairs"}};
  j["method"] = {{"Description", "rendering method (n/a for real-real pairs)"}};
  j["repetition"] = {{"Description", "0-based repetition of the design cell"}};
  j["left"] = {{"Description", "stimulus on the left square, kind:id"}};
  j["right"] = {{"Description", "stimulus on the right square, kind:id"}};
  j["attempts"] = {{"Description", "how many times the trial was started (faults re-queue it)"}};
  j["criterion"] = {{"Description", "rating criterion"}};
  j["score"] = {{"Description", "rating on the protocol's scale (0-100 by default)"},
                {"Units", "arbitrary"}};
  j["response_time"] = {{"Description", "from the end of the second stimulus to confirmation"},
                        {"Units", "s"}};
  j["rating_source"] = {{"Description",
                         "who gave the rating: 'simulated' (the simulated observer) or the "
                         "participant's input device ('window', 'rating-box:VID:PID')"}};
  j["HapticLab"] = {{"study", s.study.name},
                    {"protocol_sha256", s.study.protocol_hash},
                    {"session_status", std::string(NameOf(kSessionStatusNames, s.session.status))},
                    {"device", s.session.device},
                    {"actuator", s.session.actuator},
                    {"screens", s.session.screens},
                    {"rater", s.session.rater},
                    {"calibration", s.session.calibration},
                    {"software_version", s.session.software_version}};
  return j;
}

std::size_t WritePhysio(const internal::StreamRecording& r, const fs::path& tsv_gz,
                        const fs::path& json, const SessionRecord& s) {
  ordered_json j;
  j["SamplingFrequency"] = r.rate_hz;
  j["StartTime"] = r.chunks.empty() ? 0.0 : r.chunks.front().start_time_s;
  j["Columns"] = r.channels;
  for (const auto& c : r.channels) {
    const auto m = internal::DescribeChannel(c);
    j[c] = {{"Description", m.description}, {"Units", m.unit}};
  }
  j["RecordingDescription"] =
      "stream '" + r.stream +
      "' of the trial; StartTime is the first sample's time after the onset of this "
      "stimulus [s]";
  j["SoftwareVersions"] = s.session.software_version;
  j["Manufacturer"] = "HapticLab";
  j["DeviceSerialNumber"] = s.session.device;
  WriteJson(json, j);
  GzOut out(tsv_gz);
  const std::size_t nc = r.channels.size();
  std::size_t rows = 0;
  std::string buf;
  double next_s = j["StartTime"].get<double>();
  const std::string missing = [&] {
    std::string m;
    for (std::size_t c = 0; c < nc; ++c) m += c ? "\tn/a" : "n/a";
    return m + "\n";
  }();
  for (const auto& ch : r.chunks) {
    // A gap between chunks (dropped samples) is filled with n/a rows at the stream's rate.
    const double gap = (ch.start_time_s - next_s) * r.rate_hz;
    for (long k = 0; k < std::lround(gap); ++k, ++rows) buf += missing;
    const std::size_t n = ch.sample_count();
    for (std::size_t i = 0; i < n; ++i, ++rows) {
      for (std::size_t c = 0; c < nc; ++c) {
        if (c) buf += '\t';
        // The shortest text that reads back as the same float32.
        fmt::format_to(std::back_inserter(buf), "{}", ch.samples[i * nc + c]);
      }
      buf += '\n';
      if (buf.size() > (1u << 20)) out.Write(buf), buf.clear();
    }
    next_s = ch.start_time_s + static_cast<double>(n) / r.rate_hz;
  }
  out.Write(buf);
  out.Close();
  return rows;
}

// Participants: BIDS labels are letters and digits only; two codes that map to one label
// are refused.
struct BidsParticipants {
  std::map<std::string, std::string> label_of;  // "<study>\n<code>" -> label
  std::vector<std::vector<std::string>> rows;   // participants.tsv: id, code, study, index
  std::set<std::string> studies;
};

BidsParticipants LabelParticipants(const Database& db) {
  BidsParticipants out;
  std::map<std::string, std::string> owner;  // label -> code
  for (const auto& st : db.Studies()) {
    out.studies.insert(st.name);
    for (const auto& p : db.Participants(st.id)) {
      if (db.IsReserved(p.id)) continue;  // a code reserved by `participant new`: no data
      const std::string label = Alnum(p.code);
      const auto [it, fresh] = owner.emplace(label, p.code);
      if (!fresh)
        throw InputError(db.path(), 0, "participant.code",
                         "participants " + it->second + " and " + p.code + " (study " + st.name +
                             ") map to one BIDS label sub-" + label +
                             "; export the studies separately");
      out.label_of[st.name + "\n" + p.code] = label;
      out.rows.push_back({"sub-" + label, p.code, st.name, std::to_string(p.index)});
    }
  }
  return out;
}

// dataset_description.json and README.
void WriteDatasetDescription(const fs::path& root, const std::set<std::string>& studies,
                             std::vector<ExportedFile>& files) {
  std::string names;
  for (const auto& n : studies) names += (names.empty() ? "" : ", ") + n;
  ordered_json d;
  d["Name"] = "HapticLab study export: " + (names.empty() ? std::string("(empty)") : names);
  d["BIDSVersion"] = "1.9.0";
  d["DatasetType"] = "raw";
  d["GeneratedBy"] = {{{"Name", "HapticLab"},
                       {"Version", std::string(kVersion) + "+" + kGitSha},
                       {"Description", "hapticlab export --format bids"}}};
  WriteJson(root / "dataset_description.json", d);
  files.push_back({(root / "dataset_description.json").string(), 0});
  WriteText(root / "README", kReadme);
  files.push_back({(root / "README").string(), 0});
}

// participants.tsv and its sidecar.
void WriteParticipants(const fs::path& root, const BidsParticipants& participants,
                       std::vector<ExportedFile>& files) {
  std::string t = "participant_id\tcode\tstudy\tplan_index\n";
  for (const auto& r : participants.rows)
    t += Cell(r[0]) + "\t" + Cell(r[1]) + "\t" + Cell(r[2]) + "\t" + r[3] + "\n";
  WriteText(root / "participants.tsv", t);
  files.push_back({(root / "participants.tsv").string(), participants.rows.size()});
  ordered_json j;
  j["code"] = {{"Description", "pseudonymous participant code as stored in the study database"}};
  j["study"] = {{"Description", "study (protocol) name"}};
  j["plan_index"] = {{"Description", "participant index used to plan the trial order (0-based)"}};
  WriteJson(root / "participants.json", j);
}

// code/: the protocols and the stored material models; returns their hashes.tsv lines.
std::string WriteProtocolsAndModels(const Database& db, const fs::path& root) {
  std::string hashes;
  for (const auto& st : db.Studies()) {
    const std::string name =
        "protocol-" + (Alnum(st.name).empty() ? std::to_string(st.id) : Alnum(st.name)) + ".toml";
    WriteText(root / "code" / name, st.protocol_toml);
    hashes += "code/" + name + "\t" + st.protocol_hash + "\tstudy protocol as run\n";
  }
  internal::Stmt q(db.handle(), "SELECT name, hash, toml FROM material_model ORDER BY id");
  bool any_model = false;
  while (q.Step()) {
    if (!any_model) fs::create_directories(root / "code" / "models");
    any_model = true;
    const std::string name = Alnum(q.Text(0)) + "-" + q.Text(1).substr(0, 12) + ".toml";
    WriteText(root / "code" / "models" / name, q.Text(2));
    hashes +=
        "code/models/" + name + "\t" + q.Text(1) + "\tmaterial model stored in the database\n";
  }
  return hashes;
}

// code/hashes.tsv: the files under code/, then the models a session used but whose text the
// database does not hold (their hash only).
void WriteCode(const Database& db, const std::vector<SessionRecord>& sessions, const fs::path& root,
               std::vector<ExportedFile>& files) {
  std::string hashes = "file\tsha256\tsource\n" + WriteProtocolsAndModels(db, root);
  std::set<std::string> listed;
  for (const auto& s : sessions) {
    const auto prov = nlohmann::json::parse(s.session.provenance_json, nullptr, false);
    if (prov.is_discarded() || !prov.contains("model_hashes") || !prov["model_hashes"].is_object())
      continue;
    for (const auto& [id, h] : prov["model_hashes"].items()) {
      const std::string line = "n/a\t" + h.get<std::string>() + "\tmaterial model '" + id +
                               "' (hash from the session provenance; text not stored)\n";
      if (listed.insert(line).second && hashes.find(h.get<std::string>()) == std::string::npos)
        hashes += line;
    }
  }
  WriteText(root / "code" / "hashes.tsv", hashes);
  files.push_back({(root / "code" / "hashes.tsv").string(), 0});
}

// A session's completed trials in plan order, as the CSV export.
std::vector<const internal::TrialRecord*> InPlanOrder(const SessionRecord& s) {
  std::vector<const internal::TrialRecord*> by_plan;
  for (const auto& t : s.trials) by_plan.push_back(&t);
  std::stable_sort(by_plan.begin(), by_plan.end(), [](const auto* a, const auto* b) {
    return a->trial.plan_index < b->trial.plan_index;
  });
  return by_plan;
}

// The _beh.tsv text: one row per rating; *rows counts them.
std::string BehTable(const std::vector<const internal::TrialRecord*>& by_plan, std::size_t* rows) {
  std::string beh =
      "trial\tphase\tmaterial\tcomparison\tmethod\trepetition\tleft\tright\tattempts\tcriterion\t"
      "score\tresponse_time\trating_source\n";
  for (const auto* t : by_plan) {
    const auto& x = t->trial;
    for (const auto& r : t->ratings) {
      beh += fmt::format("{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\n", x.plan_index + 1,
                         Cell(std::string(NameOf(kPhaseKindNames, x.phase))), Cell(x.material),
                         Cell(x.comparison), Cell(x.method), x.repetition, Cell(x.left),
                         Cell(x.right), x.attempts, Cell(r.criterion), Num(r.score),
                         Num(r.response_time_s), Cell(r.source));
      ++*rows;
    }
  }
  return beh;
}

// What one participant's sessions exported (the progress line).
struct BidsCounts {
  std::size_t trials = 0, recordings = 0, samples = 0, ratings = 0;
};

// One session: sub-*/ses-*/beh/ with the ratings table, its sidecar and the physio recordings.
void WriteBidsSession(const SessionRecord& s, const std::string& sub, const fs::path& root,
                      std::vector<ExportedFile>& files, BidsCounts& n) {
  const std::string ses = "ses-" + std::to_string(s.number);
  const std::string task =
      "task-" + (Alnum(s.study.name).empty() ? std::string("study") : Alnum(s.study.name));
  const fs::path dir = root / sub / ses / "beh";
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create directory: " + ec.message());
  const std::string stem = sub + "_" + ses + "_" + task;
  const auto by_plan = InPlanOrder(s);
  std::size_t rows = 0;
  const std::string beh = BehTable(by_plan, &rows);
  WriteText(dir / (stem + "_beh.tsv"), beh);
  WriteJson(dir / (stem + "_beh.json"), BehSidecar(s));
  files.push_back({(dir / (stem + "_beh.tsv")).string(), rows});
  n.ratings += rows;
  n.trials += by_plan.size();
  for (const auto* t : by_plan)
    for (const auto& r : t->streams) {
      const std::string name = stem + "_run-" + std::to_string(t->trial.plan_index + 1) +
                               "_recording-" + Alnum(r.stream) + "_physio";
      const fs::path gz = dir / (name + ".tsv.gz");
      files.push_back({gz.string(), WritePhysio(r, gz, dir / (name + ".json"), s)});
      n.samples += files.back().rows;
      ++n.recordings;
    }
}

}  // namespace

std::vector<ExportedFile> ExportBids(const Database& db, const std::string& out_dir,
                                     const ExportProgress& progress) {
  const auto sessions = internal::LoadSessions(db, "");
  const fs::path root(out_dir);
  std::error_code ec;
  fs::create_directories(root / "code", ec);
  if (ec) throw std::runtime_error(out_dir + ": cannot create directory: " + ec.message());
  std::vector<ExportedFile> files;
  const BidsParticipants participants = LabelParticipants(db);
  WriteDatasetDescription(root, participants.studies, files);
  WriteParticipants(root, participants, files);
  WriteCode(db, sessions, root, files);
  BidsCounts n;
  for (std::size_t si = 0; si < sessions.size(); ++si) {
    const auto& s = sessions[si];
    const std::string sub =
        "sub-" + participants.label_of.at(s.study.name + "\n" + s.participant.code);
    WriteBidsSession(s, sub, root, files, n);
    // One line per participant, after their last session.
    const bool last =
        si + 1 == sessions.size() || sessions[si + 1].participant.id != s.participant.id;
    if (last && progress)
      progress(
          fmt::format("{} ({}): {} completed trials, {} ratings, {} physio recordings of {} "
                      "samples",
                      sub, s.participant.code, n.trials, n.ratings, n.recordings, n.samples));
    if (last) n = BidsCounts{};
  }
  return files;
}

ExportFormat BidsExportFormat() {
  ExportFormat f;
  f.name = "bids";
  f.help =
      "a BIDS dataset (ratings as beh/*_beh.tsv, force and vibration trajectories as\n"
      "physio recordings with unit sidecars, protocol and models under code/) that the\n"
      "official bids-validator accepts; --out DIR";
  f.write = [](const Database& db, const ExportRequest& r) {
    return ExportBids(db, r.out, r.progress);
  };
  f.describe = [](const std::vector<ExportedFile>& files) {
    std::size_t beh = 0, beh_rows = 0, physio = 0, physio_samples = 0;
    for (const auto& x : files) {
      if (x.path.ends_with("_beh.tsv")) ++beh, beh_rows += x.rows;
      if (x.path.ends_with("_physio.tsv.gz")) ++physio, physio_samples += x.rows;
    }
    return fmt::format("{} files: {} rating tables ({} ratings), {} physio recordings ({} samples)",
                       files.size(), beh, beh_rows, physio, physio_samples);
  };
  return f;
}

}  // namespace hapticlab::db
