#pragma once
/// @file The audit trail (docs/studies.md, "The audit trail"): the names for who or what
/// established the fact an event states (db::Event::established_by), and consent recorded
/// only as it happened.
///
/// Consent: a session in which a person takes part (ratings from a person's input device, or
/// a hardware device) needs the experimenter's confirmation that the participant consented
/// to the protocol's `[consent]` document and version, given on the command line
/// (`--consent-confirmed-by CODE`, RunOptions::consent_confirmed_by) or in a console that asks
/// (SessionUi::ConfirmConsent). Either way it is stored by RecordConsent as a `consent` event
/// carrying the experimenter's pseudonymous code, the document, its version and how it was
/// confirmed. A simulated session (no person) records "not applicable: simulated".

#include <cstdint>
#include <optional>
#include <string>

#include "hapticlab/db/database.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/study_runner.hpp"

namespace hapticlab::runner {

/// Values of db::Event::established_by (docs/studies.md lists which event carries which).
namespace source {
inline constexpr const char* kRunner = "hapticlab:runner";  ///< the runner's own decisions
inline constexpr const char* kPlan = "hapticlab:plan";      ///< the stored plan (breaks)
inline constexpr const char* kSessionMode = "hapticlab:session-mode";  ///< the recorded mode
inline constexpr const char* kConsole = "experimenter:console";        ///< an action in the console
inline constexpr const char* kSignal = "os:signal";                    ///< SIGINT / SIGTERM
inline constexpr const char* kDatabase = "database";  ///< the trajectory writer, SQLite
inline constexpr const char* kInjected = "simulation:inject-faults";  ///< a simulated fault
/// "experimenter:CODE": an experimenter known by a pseudonymous code.
std::string Experimenter(const std::string& code);
/// "command-line:FLAG": what the person running the command asked for (--stop-after, ...).
std::string CommandLine(const std::string& flag);
/// "device:BACKEND": the opened device back-end (and the rig file) describing itself.
std::string Device(const std::string& backend);
/// "watchdog:BACKEND": the watchdog judging the device's samples; a fault injected by the
/// simulation (`--inject-faults`) is kInjected.
std::string Watchdog(const std::string& backend, bool injected);
}  // namespace source

/// A consent confirmation: who confirmed it, against which document, and how.
struct ConsentRecord {
  std::string confirmed_by;  ///< the experimenter's pseudonymous code (e.g. "E01"), never a name
  std::string document;      ///< the protocol's `[consent] document`
  std::string version;       ///< the protocol's `[consent] version`
  std::string via;           ///< "command line" or "console"
};

/// True when a person takes part in a session run with `o`: ratings come from a person (a
/// SessionUi) or the device is hardware (no simulated rig).
bool PersonTakesPart(const RunOptions& o);

/// The consent of a session about to start (or to continue with a person) on `p` with `o`:
/// nullopt when no person takes part; else the confirmation from
/// `o.consent_confirmed_by` (via "command line") or from `o.ui->ConfirmConsent` (via
/// "console"). Writes nothing.
/// @throws InputError (field "consent_confirmed_by") when a person takes part and nobody
///         confirmed consent, when the protocol names no `[consent]` document, when the code
///         is not a pseudonymous code, or when a code is given for a simulated session
std::optional<ConsentRecord> ObtainConsent(const protocols::Protocol& p, const RunOptions& o,
                                           const std::string& participant);

/// Records a confirmed consent as the session's `consent` event (established by
/// "experimenter:CODE"): the console's consent screen calls it through the runner, the
/// command line through ObtainConsent. Returns the event id.
/// @throws InputError (field "consent_confirmed_by") when the code is not pseudonymous
///         (db::IsPseudonymousCode: letters, digits, '-', '_', at least one digit) or the
///         document, version or via is empty
std::int64_t RecordConsent(db::Database& database, std::int64_t session, const ConsentRecord& r);

/// Records that consent does not apply: no person takes part (`mode`: the session's mode,
/// SessionMode::Describe). Returns the event id.
std::int64_t RecordConsentNotApplicable(db::Database& database, std::int64_t session,
                                        const std::string& mode);

/// True when the session holds a consent confirmed by an experimenter (RecordConsent).
bool HasConfirmedConsent(const db::Database& database, std::int64_t session);

}  // namespace hapticlab::runner
