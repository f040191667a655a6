#include "hapticlab/runner/study_runner.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "adaptive_phase.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/core/version.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/trajectory_writer.hpp"
#include "hapticlab/protocols/canonical.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/runner/audit.hpp"
#include "hapticlab/runner/plan_json.hpp"
#include "hapticlab/runner/rt_engine.hpp"
#include "hapticlab/runner/study_record.hpp"
#include "lab.hpp"
#include "participant.hpp"
#include "session_queue.hpp"

namespace hapticlab::runner {
namespace {

namespace fs = std::filesystem;
using internal::Lab;
using internal::LoadLab;
using nlohmann::json;

// The stop request of RequestStop (a signal number; 0: none). Lock-free, so a signal
// handler may store to it.
std::atomic<int> g_stop_signal{0};
static_assert(std::atomic<int>::is_always_lock_free);

void Log(const RunOptions& o, const std::string& s) {
  if (o.log) o.log(s);
}

// Breaks and phase changes are logged as the plan reaches them.
void LogPlanEvents(db::Database& database, std::int64_t session,
                   const std::vector<protocols::PlannedTrial>& plan,
                   const std::vector<std::int64_t>& ids, const protocols::Protocol& p) {
  for (std::size_t i = 0; i < plan.size(); ++i)
    if (plan[i].break_before)
      database.LogEvent(
          {.session_id = session,
           .trial_id = ids[i],
           .kind = db::EventKind::kBreakPlanned,
           .detail = fmt::format("{:.0f} s break before this trial", p.break_duration_s),
           .established_by = source::kPlan});
}

// What `study resume` says when the protocol file on disk is no longer the recorded text.
std::string ProtocolOnDiskNote(const std::string& recorded, const std::string& on_disk) {
  std::vector<protocols::ProtocolChange> changes;
  try {
    changes = protocols::CanonicalDifferences(recorded, on_disk);
  } catch (const InputError&) {
    return "note: the protocol file on disk changed since the session began (it is not valid "
           "TOML now); resuming with the recorded text";
  }
  if (changes.empty())
    return "note: the protocol file on disk differs from the recorded text in comments or "
           "formatting only; resuming with the recorded text";
  std::string list;
  for (const auto& c : changes) list += (list.empty() ? "" : "; ") + c.Describe();
  return "note: the protocol file on disk changed since the session began (" + list +
         "); resuming with the recorded text";
}

// Checkpoints the WAL into the main file when a session ends, however it ends (completed,
// aborted, interrupted by a signal, or an error): the database file alone then holds every
// committed rating. Runs after ExecuteSession's trajectory writer has closed its connection.
struct CheckpointAtEnd {
  db::Database* database;
  ~CheckpointAtEnd() {
    try {
      database->Checkpoint();
    } catch (...) {  // never throw from a destructor; the -wal still holds the data
    }
  }
};

// The plan a session runs under and the models a site substituted (RunOptions): provenance
// keys "plan_sha256", "plan_site", "plan_protocol_changes" and "substituted_models" (file
// relative to the database's folder, as protocol_path, and SHA-256).
void AddPlanProvenance(const RunOptions& o, const Lab& lab, json* prov) {
  if (!o.plan_sha256.empty()) (*prov)["plan_sha256"] = o.plan_sha256;
  if (!o.plan_site.empty()) (*prov)["plan_site"] = o.plan_site;
  if (!o.plan_protocol_changes.empty()) (*prov)["plan_protocol_changes"] = o.plan_protocol_changes;
  const fs::path db_dir = fs::weakly_canonical(fs::absolute(o.db_path)).parent_path();
  for (const auto& [id, file] : o.model_files)
    (*prov)["substituted_models"][id] = {
        {"file", fs::weakly_canonical(fs::absolute(file)).lexically_relative(db_dir).string()},
        {"sha256", lab.model_hashes.count(id) ? lab.model_hashes.at(id) : ""}};
}

// The substituted models of a recorded session (AddPlanProvenance), as paths to load.
std::map<std::string, std::string> SubstitutedModels(const json& prov, const std::string& db) {
  std::map<std::string, std::string> out;
  if (!prov.contains("substituted_models") || !prov["substituted_models"].is_object()) return out;
  const fs::path db_dir = fs::weakly_canonical(fs::absolute(db)).parent_path();
  for (const auto& [id, m] : prov["substituted_models"].items())
    if (m.is_object() && m.contains("file") && m["file"].is_string())
      out[id] = (db_dir / m["file"].get<std::string>()).lexically_normal().string();
  return out;
}

// The rig a session runs on: the caller's (RunOptions::rig), or for a simulated back-end
// without one its built-in rig opened here, the generic device's link noise seeded from the
// participant.
struct SessionRig {
  std::unique_ptr<Rig> own;
  Rig* rig = nullptr;
};
SessionRig RigOf(const RunOptions& opt, std::uint64_t participant_seed) {
  if (opt.rig) return {nullptr, opt.rig};
  HL_REQUIRE(IsSimulatedBackend(opt.device),
             "a session on device '" + opt.device + "' needs RunOptions::rig (the opened device)");
  RigRequest q{.device = opt.device};
  q.generic.seed = DeriveSeed(participant_seed, 0x51D);
  SessionRig r{OpenRig(q), nullptr};
  r.rig = r.own.get();
  return r;
}

// A session's recorded actuator: its name, or "unrecorded" (before schema v5).
constexpr const char* kUnrecorded = "unrecorded";
std::string ActuatorName(const std::optional<ActuatorKind>& a) {
  return a ? std::string(NameOf(kActuatorNames, *a)) : kUnrecorded;
}

// The mode a session was recorded in, read from its row.
SessionMode RecordedModeOf(const db::Session& se, const std::string& db_path) {
  return {se.device,
          se.actuator == kUnrecorded ? std::nullopt
                                     : std::optional(ParseName(kActuatorNames, se.actuator, db_path,
                                                               0, "session.actuator")),
          se.screens, ParseRater(se.rater, db_path, "session.rater")};
}

// The run's options that need no database: the participant code, the adaptive phases the
// device can run, the site code and the site offset (checked before anything is written).
void CheckRunOptions(const protocols::Protocol& p, const RunOptions& opt) {
  protocols::CheckParticipantCode(p, opt.participant);  // before anything is written
  internal::CheckAdaptivePhases(p, opt.device, opt.ui != nullptr);
  if (const std::string why = db::SiteCodeProblem(opt.site); !why.empty())
    throw InputError("<command line>", 0, "--site",
                     "'" + opt.site + "' is not a site code (" + why +
                         "): up to 8 letters, digits, '-' or '_' with a digit, e.g. S02");
  if (opt.site_offset != 0 && PersonTakesPart(opt))
    throw InputError("<command line>", 0, "--site-offset",
                     "a site offset is added to the simulated observer's ratings; a person rates "
                     "this session");
}

// `study run` on a code that already has a session: a completed one needs a new code, any
// other is continued with 'study resume'.
[[noreturn]] void RefuseParticipantWithASession(const db::Database& database,
                                                const db::Participant& participant,
                                                const std::string& db_path) {
  const auto sessions = database.Sessions(participant.id);
  if (!sessions.empty() && sessions.back().status == db::SessionStatus::kCompleted)
    throw InputError(db_path, 0, "participant",
                     "participant " + participant.code +
                         " has already completed a session of this study; a new participant "
                         "needs a new code ('hapticlab participant new')");
  throw InputError(db_path, 0, "participant",
                   "participant " + participant.code +
                       " already has a session; continue it with 'hapticlab study resume'");
}

// The participant a run records, and its row when `participant new` reserved the code.
struct NewParticipant {
  std::optional<db::Participant> reserved;
  db::Participant part;
};
NewParticipant ParticipantOf(const db::Database& database, const protocols::Protocol& p,
                             std::int64_t study_id, const RunOptions& opt) {
  // A code reserved by `participant new` (a participant without a session) runs with the plan
  // index it was given; any other known code already has its session.
  const auto reserved = database.FindParticipant(study_id, opt.participant);
  if (reserved && !database.IsReserved(reserved->id))
    RefuseParticipantWithASession(database, *reserved, opt.db_path);
  if (reserved && opt.participant_index >= 0 && opt.participant_index != reserved->index)
    throw InputError(opt.db_path, 0, "participant",
                     fmt::format("participant {} was reserved with plan index {}; run it without "
                                 "--index or with --index {}",
                                 opt.participant, reserved->index, reserved->index));
  const int index = reserved ? reserved->index
                    : opt.participant_index >= 0
                        ? opt.participant_index
                        : static_cast<int>(database.Participants(study_id).size());
  return {reserved,
          {.study_id = study_id,
           .code = opt.participant,
           .index = index,
           .seed = protocols::ParticipantSeed(p, index)}};
}

// Provenance: everything needed to reproduce this session.
json SessionProvenance(const protocols::Protocol& p, const RunOptions& opt, const Lab& lab,
                       const std::string& hash, const db::Participant& part) {
  json models = json::object();
  for (const auto& [id, h] : lab.model_hashes) models[id] = h;
  json prov = {
      {"protocol_hash", hash},
      {"protocol_canonical_sha256", ProtocolIdentity(p)},
      // Relative to the database's folder (an absolute path would carry a user name).
      {"protocol_path",
       fs::weakly_canonical(fs::absolute(p.file))
           .lexically_relative(fs::weakly_canonical(fs::absolute(opt.db_path)).parent_path())
           .string()},
      {"study_seed", p.seed},
      {"participant_index", part.index},
      {"participant_seed", part.seed},
      {"software", std::string(kVersion) + "+" + kGitSha},
      {"device", opt.device},
      {"rig", opt.rig ? json{{"description", opt.rig->description},
                             {"file_sha256", opt.rig->rig_file_hash},
                             {"content", opt.rig->calibration}}
                      : json{{"description", "generic simulated rig"}}},
      {"model_hashes", models},
      {"masking_noise", {{"enabled", p.masking_noise}, {"level_dB", p.masking_level_dB}}}};
  if (opt.site_offset != 0) prov["observer_site_offset"] = opt.site_offset;
  AddPlanProvenance(opt, lab, &prov);
  return prov;
}

// The session row a run starts: software, device, rig, provenance, plan and mode.
db::Session SessionRow(std::int64_t participant_id, const RunOptions& opt, const SessionMode& mode,
                       const json& prov, const json& plan_json) {
  return {.participant_id = participant_id,
          .software_version = std::string(kVersion) + "+" + kGitSha,
          .device = opt.device,
          .calibration = opt.rig ? opt.rig->calibration : "simulated (no calibration)",
          // Paths in the provenance may hold bytes that are not UTF-8: replaced, not thrown.
          .provenance_json = prov.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace),
          .plan_json = plan_json.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace),
          .actuator = ActuatorName(mode.actuator),
          .screens = mode.screens,
          .rater = mode.rater.Name(),
          .site_code = opt.site};
}

// The plan's trials as rows of the session; returns their ids in plan order.
std::vector<std::int64_t> AddPlannedTrials(db::Database& database, std::int64_t session,
                                           const std::vector<protocols::PlannedTrial>& plan) {
  std::vector<db::Trial> rows;
  for (const auto& t : plan)
    rows.push_back({.session_id = session,
                    .plan_index = t.index,
                    .phase = t.phase,
                    .material = t.material,
                    .comparison = t.comparison,
                    .method = t.method,
                    .repetition = t.repetition,
                    .left = t.left,
                    .right = t.right});
  std::vector<std::int64_t> ids;
  for (const auto& r : rows) ids.push_back(database.AddTrial(r));
  return ids;
}

// The protocol a resumed session runs: the text from the database, with the folder it was run
// from (for models and profiles); a note when the file there changed since.
protocols::Protocol ResumedProtocol(const db::Study& st, const json& prov, const RunOptions& opt) {
  // Stored relative to the database's folder (older sessions: absolute).
  const std::string stored = prov.value("protocol_path", "");
  const std::string path =
      stored.empty() ? stored
                     : (fs::weakly_canonical(fs::absolute(opt.db_path)).parent_path() / stored)
                           .lexically_normal()
                           .string();
  auto p = protocols::ParseProtocol(st.protocol_toml, path);
  if (std::error_code ec;
      !path.empty() && fs::exists(path, ec) && db::HashText(ReadTextFile(path)) != st.protocol_hash)
    Log(opt, ProtocolOnDiskNote(st.protocol_toml, ReadTextFile(path)));
  return p;
}

// The mode a resumed session runs in: a change (--change-mode) is logged; a session recorded
// without its actuator (before schema v5) gets the current mode's.
void RecordResumeMode(db::Database& database, std::int64_t session, const SessionMode& recorded,
                      const SessionMode& now, bool differs, const RunOptions& opt) {
  if (differs) {
    database.LogEvent({.session_id = session,
                       .kind = db::EventKind::kModeChange,
                       .detail = fmt::format("resumed in a new mode: [{}] -> [{}]",
                                             recorded.Describe(), now.Describe()),
                       .established_by = source::CommandLine("--change-mode")});
    database.SetSessionMode(session, now.device, ActuatorName(now.actuator), now.screens,
                            now.rater.Name());
    Log(opt, fmt::format("{}: mode changed from [{}] to [{}]", opt.participant, recorded.Describe(),
                         now.Describe()));
  } else if (!recorded.actuator) {
    database.SetSessionMode(session, now.device, ActuatorName(now.actuator), now.screens,
                            now.rater.Name());
  }
}

// Reopens a session for `study resume` and logs it (with whether the previous run closed it);
// returns the number of completed trials.
int ReopenSession(db::Database& database, const db::Session& se) {
  const std::string unclosed =
      se.status == db::SessionStatus::kRunning
          ? "; the previous run ended without closing the session (killed, crashed, or a "
            "full disk)"
          : "";
  database.ReopenSession(se.id);
  int done = 0;
  for (const auto& t : database.Trials(se.id)) done += t.status == db::TrialStatus::kCompleted;
  database.LogEvent({.session_id = se.id,
                     .kind = db::EventKind::kResume,
                     .detail = fmt::format("resumed with {} of {} trials completed{}", done,
                                           database.Trials(se.id).size(), unclosed),
                     .established_by = source::CommandLine("study resume")});
  return done;
}

}  // namespace

std::string Rater::Name() const {
  return kind == RaterKind::kRatingBox ? "rating-box:" + box
         : kind == RaterKind::kWindow  ? "window"
                                       : db::kRaterSimulated;
}

Rater ParseRater(const std::string& name, const std::string& file, const std::string& field) {
  constexpr std::string_view kBox = "rating-box:";
  if (name == db::kRaterSimulated) return {};
  if (name == "window") return {RaterKind::kWindow, ""};
  if (name.size() > kBox.size() && name.compare(0, kBox.size(), kBox) == 0)
    return {RaterKind::kRatingBox, name.substr(kBox.size())};
  throw InputError(file, 0, field,
                   "expected simulated, window or rating-box:VID:PID, got '" + name + "'");
}

Rater RaterOf(bool ui, const std::string& rating_box) {
  if (!ui) return {};
  return rating_box.empty() ? Rater{RaterKind::kWindow, ""}
                            : Rater{RaterKind::kRatingBox, rating_box};
}

std::string SessionMode::Describe() const {
  return fmt::format("device {}, actuator {}, screens {}, ratings {}", device,
                     ActuatorName(actuator), screens ? "on" : "off",
                     rater.kind == RaterKind::kSimulated
                         ? "simulated"
                         : "by the participant (" + rater.Name() + ")");
}

bool CheckResumeMode(const SessionMode& recorded, const SessionMode& now, bool change_mode,
                     const std::string& db_path, const std::string& participant) {
  const bool differs = now.device != recorded.device || now.screens != recorded.screens ||
                       now.rater != recorded.rater ||
                       (recorded.actuator && now.actuator != recorded.actuator);
  if (differs && !change_mode)
    throw InputError(
        db_path, 0, "change_mode",
        fmt::format("{}'s session was recorded in mode [{}]; this resume asks for [{}]. Resume "
                    "in the recorded mode, or allow the change to continue in the new one (logged; "
                    "each rating records its source)",
                    participant, recorded.Describe(), now.Describe()));
  return differs;
}

SessionMode ModeOf(const RunOptions& o) {
  return {o.device, o.actuator, o.ui != nullptr, RaterOf(o.ui != nullptr, o.rating_box)};
}

SessionMode RecordedMode(const std::string& db_path, const std::string& participant) {
  if (std::error_code ec; !fs::exists(db_path, ec))
    throw InputError(db_path, 0, "db", "no such database");
  const db::Database database = db::OpenForReading(db_path);
  for (const auto& st : database.Studies())
    if (const auto part = database.FindParticipant(st.id, participant)) {
      const auto sessions = database.Sessions(part->id);
      if (sessions.empty())
        throw InputError(db_path, 0, "participant",
                         participant +
                             " is reserved and has no session yet; start it with 'hapticlab "
                             "study run PROTOCOL --participant " +
                             participant + "'");
      // Nothing to resume: said before any mode is compared (resume --device X on it).
      if (sessions.back().status == db::SessionStatus::kCompleted)
        throw InputError(db_path, 0, "participant",
                         participant + "'s session is already completed; nothing to resume");
      auto mode = RecordedModeOf(sessions.back(), db_path);
      mode.study = st.name;
      return mode;
    }
  throw InputError(db_path, 0, "participant",
                   "no participant " + participant + " with a session in this database");
}

void CheckRunnable(const protocols::Protocol& p, const std::string& device, bool ui) {
  internal::CheckAdaptivePhases(p, device, ui);
  (void)LoadLab(p, device);
  const bool person = ui || !IsSimulatedBackend(device);
  if (person && p.consent_document.empty())
    throw InputError(p.file, 0, "consent",
                     "a session with a person (screens or a hardware device) records the consent "
                     "document the experimenter confirmed: add [consent] document = \"...\", "
                     "version = \"...\" (docs/studies.md)");
}

void RequestStop(int signal_number) noexcept { g_stop_signal.store(signal_number); }
int StopRequested() noexcept { return g_stop_signal.load(); }

RunSummary RunStudy(const protocols::Protocol& p, const RunOptions& opt) {
  CheckRunOptions(p, opt);
  Lab lab = LoadLab(p, opt.device, opt.model_files);
  lab.profiles.observer.site_offset = opt.site_offset;
  // Consent as it happened: "not applicable" when no person takes part, else confirmed by an
  // experimenter on the command line (checked here, before anything is written) or in the
  // console, which asks below once the database accepts this participant.
  std::optional<ConsentRecord> consent;
  const bool ask_console = PersonTakesPart(opt) && opt.consent_confirmed_by.empty() && opt.ui;
  if (!ask_console) consent = ObtainConsent(p, opt, opt.participant);
  const db::WriterLease lease(opt.db_path);  // one writer per study database
  db::Database database(opt.db_path);
  const std::string hash = db::HashText(p.text);
  const SessionMode mode = ModeOf(opt);
  const std::int64_t study_id = FindOrCreateStudy(database, p, opt.db_path);
  const NewParticipant np = ParticipantOf(database, p, study_id, opt);
  const auto& reserved = np.reserved;
  const db::Participant& part = np.part;
  const auto plan = protocols::Plan(p, part.index);
  const json plan_json = PlanToJson(plan);
  const json prov = SessionProvenance(p, opt, lab, hash, part);
  if (ask_console) consent = ObtainConsent(p, opt, opt.participant);
  // Participant, session, plan and consent in one transaction: a crash leaves all or none.
  std::int64_t session;
  std::vector<std::int64_t> ids;
  {
    db::WriteTransaction tx(database);
    const auto pid = reserved ? reserved->id : database.AddParticipant(part);
    session = database.StartSession(SessionRow(pid, opt, mode, prov, plan_json));
    ids = AddPlannedTrials(database, session, plan);
    for (const auto& [id, text] : lab.model_texts) database.SaveMaterialModel(id, text);
    if (consent)
      RecordConsent(database, session, *consent);
    else
      RecordConsentNotApplicable(database, session, mode.Describe());
    LogPlanEvents(database, session, plan, ids, p);
    tx.Commit();
  }
  Log(opt, fmt::format("{}: session {} with {} planned trials ({})", opt.participant, session,
                       plan.size(), mode.Describe()));
  db::Participant stored = *database.FindParticipant(study_id, opt.participant);
  const CheckpointAtEnd checkpoint{&database};
  const SessionRig rig = RigOf(opt, stored.seed);
  return internal::ExecuteSession(database, lab, session, stored, opt, *rig.rig);
}

RunSummary ResumeStudy(const RunOptions& opt) {
  if (std::error_code ec; !fs::exists(opt.db_path, ec))
    throw InputError(opt.db_path, 0, "db", "no such database");
  const db::WriterLease lease(opt.db_path);  // one writer per study database
  db::Database database(opt.db_path);
  for (const auto& st : database.Studies()) {
    const auto part = database.FindParticipant(st.id, opt.participant);
    if (!part) continue;
    const auto sessions = database.Sessions(part->id);
    if (sessions.empty())
      throw InputError(opt.db_path, 0, "participant",
                       opt.participant +
                           " is reserved and has no session yet; start it with 'hapticlab study "
                           "run PROTOCOL --participant " +
                           opt.participant + "'");
    const auto& se = sessions.back();
    if (se.status == db::SessionStatus::kCompleted)
      throw InputError(opt.db_path, 0, "participant",
                       opt.participant + "'s session is already completed");
    const json prov = json::parse(se.provenance_json);
    auto p = ResumedProtocol(st, prov, opt);
    // The recorded mode, or with --change-mode the new one (logged).
    const SessionMode recorded = RecordedModeOf(se, opt.db_path);
    const SessionMode now = ModeOf(opt);
    const bool differs =
        CheckResumeMode(recorded, now, opt.change_mode, opt.db_path, opt.participant);
    Lab lab = LoadLab(p, opt.device, SubstitutedModels(prov, opt.db_path));
    lab.profiles.observer.site_offset = prov.value("observer_site_offset", 0.0);
    // A person takes part now but no experimenter confirmed consent yet (a simulated session
    // resumed with screens, or one recorded before schema v7), or a code is given again:
    // confirmed (or refused) before anything of this resume is written.
    if (!opt.consent_confirmed_by.empty() ||
        (PersonTakesPart(opt) && !HasConfirmedConsent(database, se.id)))
      if (const auto consent = ObtainConsent(p, opt, opt.participant))
        RecordConsent(database, se.id, *consent);
    RecordResumeMode(database, se.id, recorded, now, differs, opt);
    const int done = ReopenSession(database, se);
    Log(opt, fmt::format("{}: resuming session {} ({} trials completed; {})", opt.participant,
                         se.id, done, now.Describe()));
    const CheckpointAtEnd checkpoint{&database};
    const SessionRig rig = RigOf(opt, part->seed);
    return internal::ExecuteSession(database, lab, se.id, *part, opt, *rig.rig);
  }
  throw InputError(opt.db_path, 0, "participant",
                   "no participant " + opt.participant + " in this database");
}

}  // namespace hapticlab::runner
