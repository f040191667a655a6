#include "hapticlab/runner/audit.hpp"

#include <fmt/format.h>

#include <csignal>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/participant_code.hpp"

namespace hapticlab::runner {

namespace source {
std::string Experimenter(const std::string& code) { return "experimenter:" + code; }
std::string CommandLine(const std::string& flag) { return "command-line:" + flag; }
std::string Device(const std::string& backend) { return "device:" + backend; }
std::string Watchdog(const std::string& backend, bool injected) {
  return injected ? std::string(kInjected) : "watchdog:" + backend;
}
}  // namespace source

namespace {

constexpr const char* kField = "consent_confirmed_by";
constexpr const char* kConsentPrefix = "confirmed by experimenter ";

void CheckCode(const std::string& where, const std::string& code) {
  if (const std::string why = PseudonymousCodeProblem(code); !why.empty())
    throw InputError(where, 0, kField,
                     "'" + code + "' is not an experimenter code (" + why +
                         "): expected a pseudonymous code such as E01 (" + kPseudonymousCodeRule +
                         ")");
}

}  // namespace

bool PersonTakesPart(const RunOptions& o) {
  return o.ui != nullptr || (o.rig != nullptr && o.rig->sim == nullptr);
}

std::optional<ConsentRecord> ObtainConsent(const protocols::Protocol& p, const RunOptions& o,
                                           const std::string& participant) {
  if (!PersonTakesPart(o)) {
    if (!o.consent_confirmed_by.empty())
      throw InputError(p.file, 0, kField,
                       "no person takes part in a simulated session (simulated hand and "
                       "observer, no screens): its consent is recorded as not applicable; "
                       "leave the experimenter code out");
    return std::nullopt;
  }
  if (p.consent_document.empty())
    throw InputError(p.file, 0, "consent",
                     "a session with a person (screens or a hardware device) records the consent "
                     "document the experimenter confirmed: add [consent] document = \"...\", "
                     "version = \"...\" to the protocol (docs/studies.md)");
  ConsentRecord r{.confirmed_by = o.consent_confirmed_by,
                  .document = p.consent_document,
                  .version = p.consent_version,
                  .via = "command line"};
  if (r.confirmed_by.empty() && o.ui) {
    if (auto code = o.ui->ConfirmConsent({.study = p.name,
                                          .participant = participant,
                                          .document = r.document,
                                          .version = r.version})) {
      r.confirmed_by = *code;
      r.via = "console";
    } else if (const int sig = StopRequested()) {
      throw std::runtime_error(fmt::format(
          "stopped by signal {} ({}) while the console asked for consent; the session did not "
          "start (nothing of it recorded)",
          sig,
          sig == SIGINT    ? "SIGINT"
          : sig == SIGTERM ? "SIGTERM"
                           : "signal"));
    }
  }
  if (r.confirmed_by.empty())
    throw InputError(p.file, 0, kField,
                     fmt::format("a person takes part in this session: an experimenter must "
                                 "confirm {}'s consent to \"{}\" version \"{}\" before it starts; "
                                 "give the experimenter's code (e.g. E01), never a name",
                                 participant, r.document, r.version));
  CheckCode(p.file, r.confirmed_by);
  return r;
}

std::int64_t RecordConsent(db::Database& database, std::int64_t session, const ConsentRecord& r) {
  CheckCode(database.path(), r.confirmed_by);
  if (r.document.empty() || r.version.empty() || r.via.empty())
    throw InputError(database.path(), 0, kField,
                     "a consent record names the document, its version and how it was confirmed");
  return database.LogEvent(
      {.session_id = session,
       .kind = db::EventKind::kConsent,
       .detail = fmt::format("{}{} ({}): consent document \"{}\", version \"{}\"", kConsentPrefix,
                             r.confirmed_by, r.via, r.document, r.version),
       .established_by = source::Experimenter(r.confirmed_by)});
}

std::int64_t RecordConsentNotApplicable(db::Database& database, std::int64_t session,
                                        const std::string& mode) {
  return database.LogEvent(
      {.session_id = session,
       .kind = db::EventKind::kConsent,
       .detail = "not applicable: simulated (no person takes part; " + mode + ")",
       .established_by = source::kSessionMode});
}

bool HasConfirmedConsent(const db::Database& database, std::int64_t session) {
  for (const auto& e : database.Events(session))
    if (e.kind == db::EventKind::kConsent && e.established_by.rfind("experimenter:", 0) == 0)
      return true;
  return false;
}

}  // namespace hapticlab::runner
