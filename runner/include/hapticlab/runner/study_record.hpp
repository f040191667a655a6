#pragma once
/// @file A study's rows in the database: the protocol's identity (the SHA-256 of its
/// canonical form, protocols/canonical.hpp) checked against the one recorded, and
/// participant codes reserved before their session (`hapticlab participant new`).

#include <cstdint>
#include <string>

#include "hapticlab/db/database.hpp"
#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::runner {

/// Hex SHA-256 of the protocol's canonical form: comments and formatting leave it unchanged.
std::string ProtocolIdentity(const protocols::Protocol& p);

/// The id of p's study (by name) in `database`, created with p's text, raw-text hash and
/// identity when missing. An existing study must have been recorded with the same protocol:
/// same canonical form. A study recorded before schema v7 has no stored identity; its recorded
/// text is read and its identity filled in. When that text is not TOML (nothing this program
/// wrote) only the raw texts' hashes can be compared, and the refusal says so.
/// @throws InputError naming `db_path` and "study" when the protocol differs, listing each
///         changed key with its recorded and its new value
std::int64_t FindOrCreateStudy(db::Database& database, const protocols::Protocol& p,
                               const std::string& db_path);

struct Reservation {
  std::string code;
  int index = 0;  ///< the participant's plan index
};

/// Reserves the next free participant code of p's study in the database at `db_path`
/// (created when missing): the lowest-numbered code of protocols::InferCodeFormat(p, prefix)
/// that matches p's pattern and is not yet in the study, stored as a participant without a
/// session (plan index: the next free one), in one write transaction, so two concurrent calls
/// never return the same code. `study run --participant CODE` then runs it with that index.
/// @throws InputError as FindOrCreateStudy and InferCodeFormat
Reservation ReserveParticipant(const std::string& db_path, const protocols::Protocol& p,
                               const std::string& prefix = "");

}  // namespace hapticlab::runner
