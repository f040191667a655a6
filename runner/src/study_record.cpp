#include "hapticlab/runner/study_record.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/protocols/canonical.hpp"
#include "hapticlab/protocols/participant_code.hpp"
#include "hapticlab/runner/study_runner.hpp"

namespace hapticlab::runner {
namespace {

namespace fs = std::filesystem;

// The refusal: what changed, key by key (at most 12 listed).
[[noreturn]] void RefuseChanged(const db::Study& s, const protocols::Protocol& p,
                                const std::string& recorded_id, const std::string& db_path) {
  const auto changes = protocols::CanonicalDifferences(s.protocol_toml, p.text);
  std::string list;
  for (std::size_t i = 0; i < changes.size() && i < 12; ++i)
    list += (i ? "; " : "") + changes[i].Describe();
  if (changes.size() > 12) list += fmt::format("; and {} more", changes.size() - 12);
  throw InputError(
      db_path, 0, "study",
      fmt::format("study '{}' in this database was run with a different protocol (hash {}, "
                  "now {}); changed (recorded -> {}): {}. Use a new database or restore the "
                  "protocol",
                  p.name, recorded_id.substr(0, 12), ProtocolIdentity(p).substr(0, 12), p.file,
                  list));
}

}  // namespace

std::string ProtocolIdentity(const protocols::Protocol& p) {
  return db::HashText(protocols::CanonicalForm(p));
}

std::int64_t FindOrCreateStudy(db::Database& database, const protocols::Protocol& p,
                               const std::string& db_path) {
  const std::string identity = ProtocolIdentity(p);
  const auto s = database.FindStudy(p.name);
  if (!s)
    return database.CreateStudy({.name = p.name,
                                 .protocol_toml = p.text,
                                 .protocol_hash = db::HashText(p.text),
                                 .seed = p.seed,
                                 .protocol_canonical_sha256 = identity});
  if (!s->protocol_canonical_sha256.empty()) {
    if (s->protocol_canonical_sha256 != identity)
      RefuseChanged(*s, p, s->protocol_canonical_sha256, db_path);
    return s->id;
  }
  // Recorded before schema v7: the identity of the recorded text.
  std::string recorded;
  try {
    recorded = db::HashText(protocols::CanonicalFormOfText(s->protocol_toml, "recorded"));
  } catch (const InputError&) {
    if (s->protocol_hash == db::HashText(p.text)) return s->id;
    throw InputError(
        db_path, 0, "study",
        fmt::format("study '{}' in this database was recorded before protocols were "
                    "compared by content, and its recorded text cannot be read as "
                    "TOML: only the raw texts could be compared, and they differ "
                    "(hash {}, now {}). Use a new database or restore the protocol "
                    "file exactly",
                    p.name, s->protocol_hash.substr(0, 12), db::HashText(p.text).substr(0, 12)));
  }
  if (recorded != identity) RefuseChanged(*s, p, recorded, db_path);
  database.SetStudyCanonicalHash(s->id, recorded);
  return s->id;
}

Reservation ReserveParticipant(const std::string& db_path, const protocols::Protocol& p,
                               const std::string& prefix) {
  const protocols::CodeFormat format = protocols::InferCodeFormat(p, prefix);
  db::Database database(db_path);
  // One write transaction: a second caller waits for it (busy timeout), then sees the row.
  db::WriteTransaction tx(database);
  const std::int64_t study = FindOrCreateStudy(database, p, db_path);
  std::set<std::string> taken;
  const auto participants = database.Participants(study);
  for (const auto& x : participants) taken.insert(x.code);
  Reservation r;
  r.code = protocols::NextFreeCode(p, format, taken);
  r.index = static_cast<int>(participants.size());  // as study run picks the next one
  database.AddParticipant({.study_id = study,
                           .code = r.code,
                           .index = r.index,
                           .seed = protocols::ParticipantSeed(p, r.index)});
  tx.Commit();
  return r;
}

// ParticipantIndex and StudyStatus (study_runner.hpp): read the study's rows only.

int ParticipantIndex(const std::string& db_path, const std::string& study,
                     const std::string& code) {
  if (std::error_code ec; !fs::exists(db_path, ec))
    throw InputError(db_path, 0, "db", "no such database");
  const db::Database database = db::OpenForReading(db_path);
  const auto st = database.FindStudy(study);
  if (!st) throw InputError(db_path, 0, "participant", "no study '" + study + "' in this database");
  const auto part = database.FindParticipant(st->id, code);
  if (!part)
    throw InputError(db_path, 0, "participant",
                     "no participant " + code + " in study '" + study +
                         "' (a code not yet run or reserved has no plan index; give "
                         "--index N instead)");
  return part->index;
}

std::vector<ParticipantStatus> StudyStatus(const std::string& db_path,
                                           const std::string& participant) {
  if (std::error_code ec; !fs::exists(db_path, ec))
    throw InputError(db_path, 0, "db", "no such database");
  const db::Database database = db::OpenForReading(db_path);  // quick_check; migrates an older file
  std::vector<ParticipantStatus> out;
  for (const auto& st : database.Studies())
    for (const auto& part : database.Participants(st.id)) {
      if (!participant.empty() && part.code != participant) continue;
      ParticipantStatus s;
      s.code = part.code;
      std::map<int, int> completions;
      for (const auto& se : database.Sessions(part.id)) {
        s.session_status = se.status;
        // Faulted attempts, each re-queued: the runner's 'attempt-faulted' events (schema v7;
        // an older session counts the trials still waiting in 'faulted').
        int attempts_faulted = 0, waiting = 0;
        for (const auto& e : database.Events(se.id))
          attempts_faulted += e.kind == db::EventKind::kAttemptFaulted;
        for (const auto& t : database.Trials(se.id)) {
          ++s.planned;
          if (t.status == db::TrialStatus::kCompleted) {
            ++s.completed;
            ++completions[t.plan_index];
          }
          waiting += t.status == db::TrialStatus::kFaulted;
        }
        s.faulted += std::max(attempts_faulted, waiting);
      }
      for (const auto& [i, c] : completions) s.duplicates += c > 1 ? c - 1 : 0;
      out.push_back(s);
    }
  if (!participant.empty() && out.empty())
    throw InputError(db_path, 0, "participant",
                     "no participant " + participant + " in this database");
  return out;
}

}  // namespace hapticlab::runner
